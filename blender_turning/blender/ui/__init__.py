"""What the user sees: the Turning tab's panels and the sport presets menu."""
