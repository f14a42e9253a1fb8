"""Reading and building the scene: settings to core objects, figures and rigs, Ground meshes,
paths and crowds as objects, and the figure in the context."""
