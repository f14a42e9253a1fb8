"""Stand-ins for what a modal operator asks of Blender's window manager and context: the bpy
wheel runs in background mode, without windows (imported by the Blender tests after bpy)."""
import bpy


class WindowManager:
    """The window manager calls the modal operator makes (no windows in background mode)."""

    def __init__(self):
        self.progress = []

    def progress_begin(self, lo, hi):
        self.progress.append(("begin", lo, hi))

    def progress_update(self, value):
        self.progress.append(value)

    def progress_end(self):
        self.progress.append("end")

    def event_timer_remove(self, timer):
        pass


class Context:
    """``bpy.context`` with a stand-in window manager and workspace."""

    def __init__(self, wm):
        self.window_manager = wm
        self.workspace = type("W", (), {"status_text_set": lambda self, text: None})()

    def __getattr__(self, name):
        return getattr(bpy.context, name)
