"""The turning model and its integrators: the right-hand side on any ground, the fused kernels, the
simulation loop, the figure's parameters, grip and skidding, the trajectory."""
