"""The settings stored in a .blend file: a figure's property group (``Object.turning``) with its
nested crowd and rig groups."""
