"""Retargeting the built-in figure's motion onto the user's own rig: bone maps, the rig's fit, the
stance, the equipment."""
