"""The bound on a free pole's swing that the pole tests check (mapping/sports/skier.py)."""
from blender_turning.mapping.sports.skier import POLE_AIM_PLANT, POLE_AIM_TRAIL


def swing_bound(o, length, fps=24):
    """The most a free pole's tip may move a frame more than its grip (m): the pole's own turn
    about the grip.  A swing forward (skier.py ``_swing_forward``) turns the pole's bearing
    from trailing to planted, ``POLE_AIM_TRAIL - POLE_AIM_PLANT``, on a circle of at most its
    ``length`` and lowers the tip ``pole_lift`` (as ``1 - w**2``: at most twice that per unit
    of ``w``), ``w`` a smoothstep over at least ``pole_swing_time`` (at most 1.5 / T a second);
    the lift-out is quicker (a third of that time) but moves the tip back, with the figure."""
    turn = POLE_AIM_TRAIL - POLE_AIM_PLANT
    return 1.5 / (o.pole_swing_time * fps) * (length * turn + 2.0 * o.pole_lift)
