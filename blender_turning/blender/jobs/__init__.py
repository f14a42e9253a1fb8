"""The computations behind the operators: settings to pose track (the pipeline), the Bake Turns
job, the Follow Path planning jobs for one figure and for a crowd (worker processes), Live
Preview's re-bakes, and what the model changed, said to the user."""
