"""Path following (Section 6): the path, obstacles, moving figures as obstacles, the follow
problem, scene files and the phase post-pass."""
