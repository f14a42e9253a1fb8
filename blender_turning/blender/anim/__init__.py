"""What a bake writes onto a figure: its keys (F-curves), the NLA layers around them, the
user's own animation it sets aside, the foot track, and what the exporters need."""
