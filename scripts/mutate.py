"""Mutation check: does the test suite catch broken physics?

Applies each mutant below (a flipped sign, a dropped term, a loosened bound, a skipped check) to
the core, the mapping and the bake, one at a time, in a temporary copy of the tree (never in
place: other tools may be reading the tree), runs the test files that guard that module
(``pytest -x``, with a per-mutant timeout) and reports which mutants the tests caught, the score
and the survivors.  TESTING.md lists the survivors of the last run and why each is left.

Each mutant is located by an exact snippet that must occur exactly once in its file; if the code
has changed so that a snippet is gone (or is no longer unique), the script says which mutant and
file and stops before running anything (``--skip-stale`` runs the others and lists the stale).

    PYTHONPATH=$PWD .venv/bin/python scripts/mutate.py               # all, 2-7 minutes
    PYTHONPATH=$PWD .venv/bin/python scripts/mutate.py --only leg_force_no_omega2 ski_tilt_halved
    PYTHONPATH=$PWD .venv/bin/python scripts/mutate.py --list
    .venv/bin/python scripts/mutate.py --group bake --python .venv-bpy42/bin/python

Exit status: 0 when the score reaches ``--goal`` (0.9), 1 below it, 2 for stale mutants or a
baseline (unmutated) test run that fails.
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, replace
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PKG = "blender_turning"

# -- which tests guard which module --------------------------------------------------------------
T = "tests/"
DYNAMICS = [T + "test_mutation_guards_core.py", T + "test_dynamics.py", T + "test_one_figure.py",
            T + "test_model_kernels.py", T + "test_controllers.py"]
SIMULATE = [T + "test_mutation_guards_core.py", T + "test_one_figure.py", T + "test_controllers.py",
            T + "test_trajectory.py"]
PARAMS = [T + "test_dynamics.py", T + "test_mutation_guards_core.py", T + "test_cli_simulate.py"]
OBSTACLES = [T + "test_obstacles.py", T + "test_mutation_guards_planner.py"]
TRAJ = [T + "test_mutation_guards_core.py", T + "test_trajectory.py", T + "test_cli_simulate.py"]
PLANNER = [T + "test_mutation_guards_planner.py", T + "test_planner_search.py",
           T + "test_planner_fall_table.py"]
FUSED = [T + "test_model_kernels.py", T + "test_planner_flat_stage.py"]
MAPPING = [T + "test_mutation_guards_mapping.py", T + "test_mapping_skier.py",
           T + "test_mapping.py", T + "test_mapping_snowboarder.py",
           T + "test_mapping_telemark.py", T + "test_mapping_cyclist.py"]
TERRAIN = [T + "test_terrain.py", T + "test_terrain_symbolic.py", T + "test_terrain_sim.py",
           T + "test_terrain_fast.py", T + "test_terrain_lazy.py", T + "test_model_kernels.py"]
MODEL = [T + "test_model_kernels.py", T + "test_energy.py", T + "test_speed_is_physics.py",
         T + "test_terrain.py", T + "test_terrain_symbolic.py"]
MOVING = [T + "test_crowd_moving.py", T + "test_crowd_priority.py"]
START_CLOSE = [T + "test_crowd_start_close.py"] + MOVING
BAKE = [T + "test_blender_mutation_guards.py", T + "test_blender_bake.py",
        T + "test_blender_operators.py", T + "test_blender_robustness.py",
        T + "test_blender_layers.py"]
FOLLOW_GROUND = [T + "test_blender_follow_ground.py"]
SURFACE = [T + "test_terrain_smooth.py", T + "test_terrain_fast.py", T + "test_terrain.py",
           T + "test_terrain_lazy.py"]
CLI_GROUND = [T + "test_cli_ground.py"]
HEADING = [T + "test_mutation_guards_modules.py", T + "test_controllers.py",
           T + "test_feasible_turns.py"]
RECEDING = [T + "test_mutation_guards_modules.py", T + "test_planner_search.py"]
RETARGET = [T + "test_retarget.py"]
REGISTRY = [T + "test_registry.py", T + "test_crowd.py"]
BLENDER_REGISTRY = [T + "test_blender_registry.py"]
NOTES = [T + "test_blender_model_notes.py"]
EXPORT = [T + "test_blender_export.py"]
LIVE = [T + "test_blender_live.py", T + "test_mapping_cyclist.py"]
LIVE_RIG = [T + "test_blender_live_rig.py"]
KEY_CRC = [T + "test_key_crc.py", T + "test_blender_live.py"]
LAYERS = [T + "test_blender_layers.py", T + "test_blender_robustness.py"]
STAGING = [T + "test_crowd_staging.py", T + "test_render_job_crowd.py"]
POLES = [T + "test_blender_poles.py"]
SKIER_MAPPING = [T + "test_mapping_skier.py"]
RACING = [T + "test_racing_presets.py", T + "test_mapping_racing.py"]
SNOW_COM = RACING + [T + "test_mapping_snowboarder.py"]
LEAN_ROOM = [T + "test_racing_lean.py", T + "test_feasible_turns.py"]
LEAN_RANGE = [T + "test_lean_range.py", T + "test_cli_robust.py"]
LEAN_REPORT = [T + "test_lean_report.py", T + "test_feasible_turns.py"]


@dataclass(frozen=True)
class Mutant:
    name: str
    file: str          # relative to blender_turning/
    find: str          # exact snippet, must occur once
    replace: str
    tests: tuple
    group: str = "core"


def M(name, file, find, replace, tests, group="core"):
    return Mutant(name, file, find, replace, tuple(tests), group)


MUTANTS = [
    # -- dynamics (Section 3, Appendix A) --------------------------------------------------------
    M("forward_alpha_sign", "core/physics/dynamics.py",
      "return (body.g * s - k) / body.J", "return (body.g * s + k) / body.J", DYNAMICS),
    M("forward_alpha_no_cos", "core/physics/dynamics.py",
      "k = C_f * V * V * c / (1.0 - C_f * body.l * s)",
      "k = C_f * V * V / (1.0 - C_f * body.l * s)", DYNAMICS),
    M("inverse_cf_alpha_sign", "core/physics/dynamics.py",
      "k = body.g * s - alpha_v * body.J", "k = body.g * s + alpha_v * body.J", DYNAMICS),
    M("inverse_cf_drop_k_term", "core/physics/dynamics.py",
      "den = k * body.l * s + body.V_cm ** 2 * c", "den = body.V_cm ** 2 * c", DYNAMICS),
    M("physical_margin_loosened", "core/physics/dynamics.py",
      "PHYSICAL_MARGIN = 0.9", "PHYSICAL_MARGIN = 0.99", DYNAMICS),
    M("bound_cf_rate_doubled", "core/physics/dynamics.py",
      "step = limits.dC_f_max * tau", "step = 2.0 * limits.dC_f_max * tau", DYNAMICS),
    M("bound_cf_skip_physical", "core/physics/dynamics.py",
      "cf = xp.clip(C_f, xp.where(sin_t < 0, -lim, -cmax), xp.where(sin_t > 0, lim, cmax))",
      "cf = xp.clip(C_f, -cmax, cmax)", DYNAMICS),
    M("foot_speed_sign", "core/physics/dynamics.py",
      "return (body.V_cm if V_cm is None else V_cm) / (1.0 - C_f * body.l * s)",
      "return (body.V_cm if V_cm is None else V_cm) / (1.0 + C_f * body.l * s)", DYNAMICS),
    M("leg_force_no_omega2", "core/physics/dynamics.py",
      "along = body.m * (body.g * c + V * V_f * C_f * s - body.l * omega_v * omega_v)",
      "along = body.m * (body.g * c + V * V_f * C_f * s)", DYNAMICS),
    M("leg_force_lateral_sign", "core/physics/dynamics.py",
      "along = body.m * (body.g * c + V * V_f * C_f * s - body.l * omega_v * omega_v)",
      "along = body.m * (body.g * c - V * V_f * C_f * s - body.l * omega_v * omega_v)", DYNAMICS),
    M("leg_force_across_times_l", "core/physics/dynamics.py",
      "across = body.I_v * alpha_v / body.l", "across = body.I_v * alpha_v * body.l", DYNAMICS),
    M("batch_heading_rate_C_f", "core/physics/dynamics.py",
      "return (V_f * xp.cos(d), V_f * xp.sin(d), V_f * cf, state[OMEGA_V], alpha)",
      "return (V_f * xp.cos(d), V_f * xp.sin(d), cf, state[OMEGA_V], alpha)", DYNAMICS),
    M("batch_alpha_no_ratio", "core/physics/dynamics.py",
      "alpha = (body.g * s - cf * V * V * c * ratio) / body.J",
      "alpha = (body.g * s - cf * V * V * c) / body.J", DYNAMICS),
    M("rk4_to_euler", "core/physics/dynamics.py",
      "return state + (dt / 6.0) * (k1 + 2.0 * (k2 + k3) + k4)", "return state + dt * k1",
      DYNAMICS),
    # -- one figure on floats ------------------------------------------------------------------
    M("one_alpha_sign", "core/physics/one_figure.py",
      "alpha = (g * s - cf * VV * c * ratio) / J",
      "alpha = (g * s + cf * VV * c * ratio) / J", DYNAMICS),
    M("one_heading_rate_C_f", "core/physics/one_figure.py",
      "return V_f * cos(x2), V_f * sin(x2), V_f * cf, x4, alpha, cf, alpha, V_f",
      "return V_f * cos(x2), V_f * sin(x2), cf, x4, alpha, cf, alpha, V_f", DYNAMICS),
    M("one_fall_right_undetected", "core/physics/one_figure.py",
      "if abs(x3) > fall:", "if x3 > fall:", DYNAMICS),
    M("one_rate_doubled", "core/physics/one_figure.py",
      "step = rate * tau", "step = 2.0 * rate * tau", DYNAMICS),
    M("one_skip_physical_low", "core/physics/one_figure.py",
      "lo = -cmax if ls >= 0.0 else max(-cmax, PHYSICAL_MARGIN / ls)", "lo = -cmax", DYNAMICS),
    M("one_inverse_sign", "core/physics/one_figure.py",
      "k = lg * s - law(t, x3, x4) * lJ", "k = lg * s + law(t, x3, x4) * lJ", DYNAMICS),
    # -- simulate, phase -----------------------------------------------------------------------
    M("batch_fall_right_undetected", "core/physics/simulate.py",
      "np.any(np.abs(state[THETA_V]) > limits.theta_fall)",
      "np.any(state[THETA_V] > limits.theta_fall)", SIMULATE),
    M("s_at_V_cm", "core/physics/simulate.py",
      'ds = 0.5 * (cols["V_f"][1:] + cols["V_f"][:-1]) * dt',
      'ds = np.full_like(cols["V_f"][1:], body.V_cm * dt)', SIMULATE),
    M("F_leg_along_only", "core/physics/simulate.py",
      'cols["C_f"], V_cm)[0]', 'cols["C_f"], V_cm)[1]', SIMULATE),
    M("phase_arctan", "core/controllers/phase.py",
      "return np.mod(np.arctan2(y, x), TWO_PI)", "return np.mod(np.arctan(y / x), TWO_PI)",
      SIMULATE + [T + "test_phase_estimate.py"]),
    M("open_loop_alpha_sign", "core/controllers/phase.py",
      "return -omega0 * omega0 * theta_max * backend(phi).sin(phi)",
      "return omega0 * omega0 * theta_max * backend(phi).sin(phi)", SIMULATE),
    # -- params --------------------------------------------------------------------------------
    M("l_unchecked", "core/physics/params.py",
      'for name in ("m", "l", "I_v", "V_cm", "g"):', 'for name in ("m", "I_v", "V_cm", "g"):',
      PARAMS),
    M("J_drops_l", "core/physics/params.py",
      "return (self.I_v + self.l * self.l * self.m) / (self.m * self.l)",
      "return (self.I_v + self.l * self.m) / (self.m * self.l)", PARAMS),
    M("mass_zero_allowed", "core/ranges.py",
      '"m": Range(1.0, 1000.0, "kg"', '"m": Range(-1.0, 1000.0, "kg"', PARAMS),
    M("theta_fall_unchecked", "core/physics/params.py",
      'check("theta_fall", self.theta_fall, "theta_fall")', "pass", PARAMS),
    # -- obstacles (Section 6) -----------------------------------------------------------------
    M("edge_clearance_ignored", "core/course/obstacles.py",
      "hit[i[d <= cl]] = True", "hit[i[d <= 0.0]] = True", OBSTACLES),
    M("circle_clearance_ignored", "core/course/obstacles.py",
      "r = c[:, 2] + cl", "r = c[:, 2]", OBSTACLES),
    M("polygon_inside_skipped", "core/course/obstacles.py",
      "hit |= _inside(a, p)", "pass", OBSTACLES),
    M("near_drops_clearance", "core/course/obstacles.py",
      "r = radius + self.clearance", "r = radius", OBSTACLES),
    M("box_prefilter_no_clearance", "core/course/obstacles.py",
      "lo = np.minimum(a, b)[:, None] - cl", "lo = np.minimum(a, b)[:, None]", OBSTACLES),
    M("point_segment_unclipped", "core/course/obstacles.py",
      "t = np.clip(np.where(den > 0, t, 0.0), 0.0, 1.0)", "t = np.where(den > 0, t, 0.0)",
      OBSTACLES),
    M("collinear_counts_as_crossing", "core/course/obstacles.py",
      "crossing = (d1 * d2 <= 0) & (d3 * d4 <= 0) & "
      "((d1 != 0) | (d2 != 0) | (d3 != 0) | (d4 != 0))",
      "crossing = (d1 * d2 <= 0) & (d3 * d4 <= 0)", OBSTACLES),
    M("min_distance_inside_positive", "core/course/obstacles.py",
      "d = np.where(_inside(p, poly), -np.abs(d), d)", "d = d", OBSTACLES),
    # -- trajectory I/O (the contract) ---------------------------------------------------------
    M("csv_header_unchecked", "core/physics/trajectory.py",
      "if header not in (COLUMNS, CARVED_COLUMNS, LEGACY_COLUMNS):", "if not header:", TRAJ),
    M("csv_low_precision", "core/physics/trajectory.py",
      'rows += [",".join(map(repr, row)) for row in self.data.T.tolist()]',
      'rows += [",".join(f"{v:.6g}" for v in row) for row in self.data.T.tolist()]', TRAJ),
    M("resample_heading_rate_C_f", "core/physics/trajectory.py",
      '"theta_dir": V_f * C_f,', '"theta_dir": C_f,', TRAJ),
    # -- the model on any ground (core/physics/model.py; docs/TERRAIN.md) --------------------------
    M("terrain_lateral_gravity_sign", "core/physics/model.py",
      "(fr.g_lateral - V * V_f * cf) * c", "(-fr.g_lateral - V * V_f * cf) * c", MODEL),
    M("terrain_no_normal_acceleration", "core/physics/model.py",
      "G_n = fr.g_normal + V_f * V_f * fr.kappa_n", "G_n = fr.g_normal", MODEL),
    M("terrain_normal_force_static", "core/physics/model.py",
      "N = body.m * (G_n - body.l * (alpha * s + om * om * c))", "N = body.m * G_n", MODEL),
    M("terrain_friction_flat_load", "core/physics/model.py",
      "resistance.mu * N / body.m", "resistance.mu * body.g", MODEL),
    M("terrain_heading_rate_flat", "core/physics/model.py",
      "turn = V_f * (cf * fr.turn_gain + fr.kappa_n * fr.bend_gain)", "turn = V_f * cf", MODEL),
    M("model_heading_rate_no_curved_ground_term", "core/physics/model.py",
      "turn = V_f * (cf * fr.turn_gain + fr.kappa_n * fr.bend_gain)",
      "turn = V_f * (cf * fr.turn_gain)", MODEL),
    M("model_heading_rate_no_turn_gain", "core/physics/model.py",
      "turn = V_f * (cf * fr.turn_gain + fr.kappa_n * fr.bend_gain)",
      "turn = V_f * (cf + fr.kappa_n * fr.bend_gain)", MODEL),
    M("terrain_drag_double", "core/physics/model.py",
      "return self.rho * self.CdA / (2.0 * m)", "return self.rho * self.CdA / m", MODEL),
    M("terrain_inverse_no_lateral", "core/physics/model.py",
      "k = G_n * s + frame.g_lateral * c - alpha_v * body.J", "k = G_n * s - alpha_v * body.J",
      MODEL),
    M("model_inverse_no_curvature", "core/physics/model.py",
      "    G_n = frame.g_normal + V * V * frame.kappa_n\n    k =",
      "    G_n = frame.g_normal\n    k =", MODEL),
    M("model_eq21_sign", "core/physics/model.py",
      "ratio = 1.0 / (1.0 - cf * body.l * s)", "ratio = 1.0 / (1.0 + cf * body.l * s)", MODEL),
    M("model_alpha_gravity_flat", "core/physics/model.py",
      "alpha = (G_n * s + (fr.g_lateral", "alpha = (body.g * s + (fr.g_lateral", MODEL),
    M("model_alpha_no_centripetal", "core/physics/model.py",
      "(fr.g_lateral - V * V_f * cf) * c", "(fr.g_lateral) * c", MODEL),
    M("model_position_at_body_speed", "core/physics/model.py",
      "deriv = (V_f * tx, V_f * ty,", "deriv = (V * tx, V * ty,", MODEL),
    M("model_lean_rate_sign", "core/physics/model.py",
      "deriv = (V_f * tx, V_f * ty, turn, om, alpha, dV)",
      "deriv = (V_f * tx, V_f * ty, turn, -om, alpha, dV)", MODEL),
    M("model_speed_no_gravity", "core/physics/model.py",
      "dV = (fr.g_along - resistance.mu", "dV = (0.0 - resistance.mu", MODEL),
    M("model_speed_gravity_at_foot_speed", "core/physics/model.py",
      "dV = (fr.g_along - resistance.mu", "dV = (fr.g_along * ratio - resistance.mu", MODEL),
    M("model_friction_at_body_speed", "core/physics/model.py",
      "resistance.mu * N / body.m * ratio", "resistance.mu * N / body.m", MODEL),
    M("model_no_lean_share", "core/physics/model.py",
      "+ body.l * om * c * V_f * cf)", ")", MODEL),
    M("model_held_ignored", "core/physics/model.py", "    if held:\n", "    if False:\n", MODEL),
    M("model_speed_held_on_any_ground", "core/physics/model.py",
      'return bool(getattr(ground, "flat", False)) and resistance.free',
      "return resistance.free", MODEL + [T + "test_terrain_sim.py"]),
    M("model_plumb_lean_sign", "core/physics/model.py",
      "return math.atan2(-frame.g_lateral, frame.g_normal)",
      "return math.atan2(frame.g_lateral, frame.g_normal)", MODEL + [T + "test_terrain_sim.py"]),
    M("model_leg_force_lateral_sign", "core/physics/model.py",
      "(V * V_f * C_f - frame.g_lateral) * s", "(V * V_f * C_f + frame.g_lateral) * s", MODEL),
    M("model_leg_force_no_omega2", "core/physics/model.py",
      "                      - body.l * omega_v * omega_v)", "                      )", MODEL),
    M("model_rk4_to_euler", "core/physics/model.py",
      "return state + (dt / 6.0) * (k1 + 2.0 * (k2 + k3) + k4)", "return state + dt * k1", MODEL),
    M("speed_checked_against_user_range", "core/physics/params.py",
      'body.__dict__["V_cm"] = float(V_cm)', 'body.__dict__["V_cm"] = check("V_cm", V_cm, "V_cm")',
      [T + "test_speed_is_physics.py"]),
    M("terrain_kappa_one_inv_t", "core/ground/terrain.py",
      "* inv_n * inv_t * inv_t", "* inv_n * inv_t", TERRAIN),
    M("terrain_normal_gravity_flat", "core/ground/terrain.py",
      "g_normal=g * nz,", "g_normal=g,", TERRAIN),
    M("terrain_left_flipped", "core/ground/terrain.py",
      "bx, by, bz = ny * tz - nz * ty, nz * tx - nx * tz, nx * ty - ny * tx",
      "bx, by, bz = nz * ty - ny * tz, nx * tz - nz * tx, ny * tx - nx * ty", TERRAIN),
    # -- the height field's biquintic (core/ground/terrain.py, docs/TERRAIN.md Section 1) ----------
    M("heightfield_weight_typo", "core/ground/terrain.py",
      "[0.0, -1.0, 1.0, 3.0, -5.0, 2.0],", "[0.0, -1.0, 1.0, 3.0, -5.0, 2.5],", SURFACE),
    M("heightfield_float_hyy_factor", "core/ground/terrain.py",
      "v * (12.0 * r4 + v * 20.0 * r5)", "v * (6.0 * r4 + v * 20.0 * r5)", SURFACE),
    M("heightfield_float_hxy_factor", "core/ground/terrain.py",
      "hxy = (d1 + v * (2.0 * d2", "hxy = (d1 + v * (d2", SURFACE),
    M("heightfield_cell_second_u_factor", "core/ground/terrain.py",
      "Auu = Au[:, 1:] * _POW[1:-1]", "Auu = Au[:, 1:] * _POW[2:]", SURFACE),
    M("heightfield_cell_base_lost", "core/ground/terrain.py", "A[0, 0] += base", "pass", SURFACE),
    M("heightfield_array_base_lost", "core/ground/terrain.py",
      "return (base + ev(wy, wx),", "return (ev(wy, wx),", SURFACE),
    M("heightfield_weights_derivative_order", "core/ground/terrain.py",
      "ddpowers = _POW * (_POW - 1.0) * u ** np.maximum(_POW - 2.0, 0.0)",
      "ddpowers = _POW * u ** np.maximum(_POW - 2.0, 0.0)", SURFACE),
    # -- simulate --ground (cli/terrain_flags.py) ---------------------------------------------
    M("cli_ground_origin_swapped", "cli/terrain_flags.py",
      '"origin": [x0, y0]}', '"origin": [y0, x0]}', CLI_GROUND),
    M("cli_ground_flags_ignored", "cli/terrain_flags.py",
      'base = read_ground(args, sport)\n        out["resistance"] = replace(base, **given)',
      'base = read_ground(args, sport)\n        out["resistance"] = base',
      CLI_GROUND),
    M("cli_ground_start_ignored", "cli/simulate.py",
      "slalom_start(fig.body, w0, tm0, heading(0.0), x0, y0)",
      "slalom_start(fig.body, w0, tm0, heading(0.0))", CLI_GROUND),
    M("cli_target_speed_traverses", "cli/simulate.py",
      "        return math.degrees(ground.downhill)\n", "        return -90.0\n",
      [T + "test_cli_skidding.py"]),
    M("json_reader_deep_nesting_unreported", "core/validate.py",
      "    except RecursionError:\n        raise FieldError(f\"{what} {str(path)!r} is nested too deeply\") from None\n",
      "", [T + "test_cli_robust.py", T + "test_cli_crowd_failures.py"]),
    # -- the half-turn's heading change (core/controllers/heading_table.py, Section 5.2) -----------
    M("heading_table_no_inertia_term", "core/controllers/heading_table.py",
      "return th * (self._gv * A / w + self._jv * w * B)", "return th * (self._gv * A / w)",
      HEADING),
    M("heading_table_float_no_inertia_term", "core/controllers/heading_table.py",
      "return th * (self._gv * A / omega0 + self._jv * omega0 * B)",
      "return th * (self._gv * A / omega0)", HEADING),
    M("heading_table_B_cos_inverted", "core/controllers/heading_table.py",
      "B = (np.sin(u) / np.cos(ts)) @ w", "B = (np.sin(u) * np.cos(ts)) @ w", HEADING),
    M("heading_table_beta_wrong_end", "core/controllers/heading_table.py",
      "return np.where(F(lo) >= 0, lo, np.where(F(hi) <= 0, hi, beta))",
      "return np.where(F(lo) >= 0, lo, np.where(F(hi) <= 0, lo, beta))", HEADING),
    M("heading_table_float_bracket_flipped", "core/controllers/heading_table.py",
      "            if f <= 0:\n                a = beta",
      "            if f > 0:\n                a = beta", HEADING),
    # -- the feasible turns (core/controllers/feasible.py) ------------------------------------
    M("feasible_rate_no_lean_rate", "core/controllers/feasible.py",
      "* np.sqrt(w2) * tm * np.cos(_PHASES)", "* np.sqrt(w2) * tm", HEADING),
    M("feasible_rate_sign", "core/controllers/feasible.py",
      "+ k * VV * s - k * k * l * c", "- k * VV * s - k * k * l * c", HEADING),
    M("feasible_no_lean_margin", "core/controllers/feasible.py",
      "fall - LEAN_MARGIN if fall > 2 * LEAN_MARGIN", "fall if fall > 2 * LEAN_MARGIN", HEADING),
    M("feasible_no_cf_share", "core/controllers/feasible.py",
      "self.allowed = (CF_SHARE * limits.C_f_max,", "self.allowed = (limits.C_f_max,", HEADING),
    M("feasible_beta_frequency_inverted", "core/controllers/feasible.py",
      "return b * theta_max <= self.max_lean(omega0 / b) * (1 + 1e-12)",
      "return b * theta_max <= self.max_lean(omega0 * b) * (1 + 1e-12)", HEADING),
    M("feasible_table_stops_early", "core/controllers/feasible.py",
      "done = hi - lo <= LEAN_TOL", "done = hi - lo <= 1e3 * LEAN_TOL", HEADING),
    M("feasible_table_infeasible_end", "core/controllers/feasible.py",
      "lean[i[done]] = lo[done]", "lean[i[done]] = hi[done]", HEADING),
    M("feasible_nearby_key_without_gravity", "core/controllers/feasible.py",
      '_BODY_FIELDS = ("m", "l", "I_v", "V_cm", "g")', '_BODY_FIELDS = ("m", "l", "I_v", "V_cm")',
      HEADING),
    M("feasible_nearby_key_without_limits", "core/controllers/feasible.py",
      "if abs(b.V_cm - V) / V <= rel and lim == limits]",
      "if abs(b.V_cm - V) / V <= rel]", HEADING),
    M("feasible_nearby_takes_newest", "core/controllers/feasible.py",
      "min(near, key=lambda n: (n[0], -n[1]))", "max(near, key=lambda n: n[1])", HEADING),
    # -- receding-horizon following (core/planner/receding.py, Section 6.1) -------------------
    M("receding_applies_last_choice", "core/planner/receding.py",
      "np.array([plan.u[0]]), np.array([t])", "np.array([plan.u[-1]]), np.array([t])",
      RECEDING),
    M("receding_distance_left_sum", "core/planner/receding.py",
      "ds = 0.5 * (V[1:] + V[:-1]) * np.diff(T)", "ds = V[:-1] * np.diff(T)", RECEDING),
    M("receding_end_rates_stale", "core/planner/receding.py",
      "A[-1], V[-1] = float(np.ravel(a_end)[0]), float(np.ravel(v_end)[0])",
      "A[-1], V[-1] = A[-2], V[-2]", RECEDING),
    # -- terrain, the fused float stepper of one figure (core/physics/terrain_one_figure.py) -------
    M("fused_lateral_gravity_sign", "core/physics/terrain_one_figure.py",
      "(g_b - V * V_f * cf) * cs", "(-g_b - V * V_f * cf) * cs", TERRAIN),
    M("fused_no_normal_acceleration", "core/physics/terrain_one_figure.py",
      "G_n = g_n + V_f * V_f * kappa", "G_n = g_n", TERRAIN),
    M("fused_normal_force_static", "core/physics/terrain_one_figure.py",
      "N_m = G_n - l * (alpha * sn + om * om * cs)", "N_m = G_n", TERRAIN),
    M("fused_friction_at_body_speed", "core/physics/terrain_one_figure.py",
      "mu * N_m * ratio", "mu * N_m", TERRAIN),
    M("fused_no_lean_share", "core/physics/terrain_one_figure.py",
      " + l * om * cs * V_f * cf", "", TERRAIN),
    M("fused_heading_rate_no_bend", "core/physics/terrain_one_figure.py",
      "(cf * (w * w) + kappa * across * w)", "(cf * (w * w))", TERRAIN),
    M("fused_inverse_no_curvature", "core/physics/terrain_one_figure.py",
      "k = ((g_n + VV * kappa) * sn", "k = ((g_n) * sn", TERRAIN),
    M("fused_plumb_along_unnormalized", "core/physics/terrain_one_figure.py",
      "                    eq = atan((hy * cH - hx * sH) / sqrt(1.0 + q * q))",
      "                    eq = atan((hy * cH - hx * sH))", TERRAIN),
    M("fused_lean_not_relative", "core/physics/terrain_one_figure.py",
      "law(t, th - eq, om)", "law(t, th, om)", TERRAIN),
    M("fused_no_rate_bound", "core/physics/terrain_one_figure.py",
      "if rated and anchor is not None:", "if False:", TERRAIN),
    M("feasible_ellipse_memo_stale", "core/controllers/ellipse.py",
      "                self._forget()                  # the ellipses made feasible by the old table",
      "                pass", [T + "test_braking.py"]),
    M("batch_ellipse_kept_after_new_table", "core/controllers/ellipse.py",
      "        self._batch = None ", "        self._batch = getattr(self, '_batch', None) ",
      [T + "test_batch.py"]),
    M("batch_beta_range_lo_for_hi", "core/controllers/ellipse.py",
      "return kept[3][0][idx], kept[3][1][idx]", "return kept[3][0][idx], kept[3][0][idx]",
      [T + "test_batch.py", T + "test_crowd_kernels.py"]),
    M("dask_workers_config_dropped", "crowd/dask_workers.py",
      "dask.config.set(WORKER_CONFIG if config is None else config)", "dask.config.set({})",
      [T + "test_crowd_parallel.py"]),
    M("dask_workers_environ_levels", "crowd/dask_workers.py",
      'key.upper().replace(".", "__")', 'key.upper().replace(".", "_")',
      [T + "test_crowd_parallel.py"]),
    M("braking_integral_unheld", "core/controllers/braking.py",
      "        if not held:\n            self.integral", "        if True:\n            self.integral",
      [T + "test_braking.py"]),
    M("heightfield_cell_polynomial", "core/ground/terrain.py",
      "e3 = q30 + u * (q31 + u * (q32 + u * q33))", "e3 = q30 + u * (q31 + u * q32)", TERRAIN),
    M("lazy_extension_flipped", "core/ground/terrain.py",
      "k = np.where(idx < 0, -idx,", "k = np.where(idx < 0, idx,", TERRAIN),
    M("lazy_stencil_one_tile_row", "core/ground/terrain.py",
      "a0, a1, b0, b1 = r0 // T, (r0 + 3) // T,", "a0, a1, b0, b1 = r0 // T, r0 // T,", TERRAIN),
    # -- planner (Section 6) -------------------------------------------------------------------
    M("v_max_without_eq21", "core/planner/problem.py",
      "self.v_max = self.speed.max / (1.0 - slip)", "self.v_max = self.speed.max", PLANNER),
    M("lipschitz_step_halved", "core/planner/problem.py",
      "b = self.v_max * st.sample_dt\n", "b = 0.5 * self.v_max * st.sample_dt\n", PLANNER),
    M("lower_bound_doubled", "core/planner/problem.py",
      "return self.total_bound(terms, d_last, depth, state).reshape(d_last.shape)",
      "return 2.0 * self.total_bound(terms, d_last, depth, state).reshape(d_last.shape)",
      PLANNER),
    M("planner_fall_right_undetected", "core/planner/problem.py",
      "fell |= ~(np.abs(P[1:, THETA_V]) <= st.theta_bound)",
      "fell |= ~(P[1:, THETA_V] <= st.theta_bound)", PLANNER),
    M("arc_radius_halved", "core/planner/problem.py",
      "return r[:, per - 1::per] * (1 + 1e-6) + 1e-9",
      "return 0.5 * r[:, per - 1::per] * (1 + 1e-6) + 1e-9", PLANNER),
    M("spread_past_the_rate", "core/planner/problem.py",
      "return frac * np.clip(room / self.settings.t_stage, 0.0, lim.dC_f_max)",
      "return frac * np.clip(room / self.settings.t_stage, 0.0, None)",
      [T + "test_planner_spread.py"]),
    M("spread_even_side_unscaled", "core/planner/problem.py",
      "room = lim.C_f_max - np.copysign(1.0, frac) * np.asarray(C_f, float)",
      "room = lim.C_f_max - np.asarray(C_f, float)", [T + "test_planner_spread.py"]),
    M("spread_scene_key_ignored", "core/course/scene.py",
      '"spread": pl.string("spread", "rate", choices=SPREADS)}', "}",
      [T + "test_planner_race.py"]),
    M("spread_drops_unlike_siblings", "core/planner/search.py",
      "same[:, j] = (u[:, :j] == u[:, j:j + 1]).any(axis=1)",
      "same[:, j] = np.isclose(u[:, :j], u[:, j:j + 1], atol=0.3).any(axis=1)",
      [T + "test_planner_spread.py"]),
    M("reach_support_halved", "core/planner/reach.py",
      "self.H = H * (1 + 1e-9) + 1e-9", "self.H = 0.5 * H", PLANNER),
    M("pair_floor_a_doubled", "core/planner/spacing.py",
      "self.a = st.sample_dt * v_min", "self.a = 2.0 * st.sample_dt * v_min", PLANNER),
    M("queue_clip_too_early", "core/planner/search.py",
      "if prio > ub + tol():", "if prio > 0.8 * ub + tol():", PLANNER),
    # -- the fused stage: the same RK4 as the generic one --------------------------
    M("fused_alpha_gravity_sign", "core/planner/flat_stage.py",
      "np.subtract(out[4], a, out=out[4])", "np.add(out[4], a, out=out[4])", FUSED),
    M("fused_floats_half_step_full", "core/planner/flat_stage.py",
      "vf * c2, om + half * ao,", "vf * c2, om + h * ao,", FUSED),
    M("fused_fourth_stage_rate_halved", "core/planner/flat_stage.py",
      "np.maximum(D[2:-1:3], first - sh), first + sh)",
      "np.maximum(D[2:-1:3], first - shalf), first + shalf)", FUSED),
    # -- path following ------------------------------------------------------
    M("body_not_checked", "core/planner/problem.py",
      "foot, body = track[:2], self.body_point(track)",
      "foot, body = track[:2], track[:2]", [T + "test_planner_body.py"]),
    M("body_on_the_wrong_side", "core/planner/problem.py",
      "state[Y] + off * np.cos(th)", "state[Y] - off * np.cos(th)", [T + "test_planner_body.py"]),
    M("end_by_half_plane", "core/course/path.py",
      "return bool(p >= self.length and crossed)", "return bool(crossed)",
      [T + "test_path.py", T + "test_cli_follow.py"]),
    M("progress_jumps_ahead", "core/course/path.py",
      "p + 2.0 * travel + self.spacing", "p + self.near", [T + "test_path.py"]),
    M("dead_ends_not_avoided", "core/planner/viable.py",
      "    if not problem.settings.viable_stages:\n        return np.zeros(len(C_f), bool)\n"
      "    return no_way_on(", "    if True:\n        return np.zeros(len(C_f), bool)\n"
      "    return no_way_on(", [T + "test_planner_search.py"]),
    # -- figures avoiding each other (core/course/moving.py) --------------------------------
    M("movers_without_time", "core/planner/problem.py",
      "self.movers.collides(foot, body, t0, st.dt)",
      "self.movers.collides(foot, body, 0.0 * t0, st.dt)", MOVING),
    M("movers_without_body_point", "core/planner/problem.py",
      "self.movers.collides(foot, body, t0, st.dt)",
      "self.movers.collides(foot, foot, t0, st.dt)", MOVING),
    M("movers_window_one_stage", "core/planner/problem.py",
      "t + (st.n_stages + 1) * st.t_stage * 1.001 + st.dt", "t + st.t_stage", MOVING),
    M("movers_lipschitz_ignored", "core/course/moving.py",
      "idx = np.flatnonzero(~hit & (0.5 * (d0 + d1 - L) <= cl))",
      "idx = np.flatnonzero(~hit & (0.5 * (d0 + d1) <= cl))", MOVING),
    M("movers_doubt_not_counted", "core/course/moving.py",
      "    hit[idx] = True                            # still in doubt", "    pass  #", MOVING),
    M("movers_cm_on_the_right", "core/course/moving.py",
      "x - side * np.sin(head), y + side * np.cos(head)",
      "x + side * np.sin(head), y - side * np.cos(head)", MOVING),
    M("closest_cells_bound_loose", "core/course/moving.py",
      "bound = math.inf if whole else h - 2.0 * r", "bound = math.inf if whole else h + 2.0 * r",
      [T + "test_crowd_moving.py"]),
    M("closest_cells_same_body", "core/course/moving.py",
      "keep = jj[q] != jj[t]", "keep = jj[q] >= 0", [T + "test_crowd_moving.py"]),
    M("max_leans_numpy_log", "core/controllers/feasible.py",
      "np.fromiter(map(math.log, w.ravel()), float, w.size).reshape(w.shape)", "np.log(w)",
      [T + "test_feasible_turns.py"]),
    M("movers_near_window_short", "core/course/moving.py",
      "min(int(math.ceil(t_hi / self.dt)) - self.m0 + 2, n)",
      "min(int(math.ceil(t_hi / self.dt)) - self.m0 - 5, n)", MOVING),
    M("groups_never_see_each_other", "crowd/priority.py",
      "            if body.seen_by(region).any():", "            if False:", MOVING),
    M("bodies_on_the_crowds_clock", "crowd/priority.py",
      "shift=f.time_offset, log=log)", "shift=0.0, log=log)", MOVING),
    # -- figures that start close (crowd/priority.py, docs/crowds.md) -------------------------
    M("start_close_keeps_the_clearance", "crowd/priority.py",
      "            out[k] = START_SHARE * d", "            pass", START_CLOSE),
    M("start_close_keeps_all_of_it", "crowd/priority.py",
      "START_SHARE = 0.5", "START_SHARE = 1.0", START_CLOSE),
    M("start_close_every_pair", "crowd/priority.py",
      "        if d <= clearance:", "        if d <= 10.0 * clearance:", START_CLOSE),
    M("start_close_at_the_crowds_start", "crowd/priority.py",
      "float(np.interp(f.time_offset, tr.t, v))", "float(np.interp(tr.t[0], tr.t, v))",
      START_CLOSE),
    M("start_close_body_upright", "crowd/priority.py",
      "    side = f.figure.body.l * np.sin(lean)", "    side = 0.0 * lean", START_CLOSE),
    M("movers_one_clearance_for_all", "core/course/moving.py",
      "cl = cl[near]                                     # (B, 1)",
      "cl = cl[near].max() + 0.0 * cl[near]              # (B, 1)", START_CLOSE),
    M("movers_near_drops_the_clearances", "core/course/moving.py",
      "else self.clearance[keep]", "else self.clearance", START_CLOSE),
    M("movers_in_doubt_other_pairs_clearance", "core/course/moving.py",
      "        c = cl[idx]\n", "        c = cl[::-1][idx]\n", START_CLOSE),
    # -- mapping (Section 7) -------------------------------------------------------------------
    M("retarget_swing_small_angle", "mapping/retarget/retarget.py",
      "vx @ vx / np.where(opp, 1.0, 1.0 + c)", "vx @ vx / np.where(opp, 1.0, 2.0)", RETARGET,
      "mapping"),
    M("retarget_knee_slide_other_root", "mapping/retarget/retarget.py",
      "return -wu + np.sqrt(np.maximum(", "return -wu - np.sqrt(np.maximum(", RETARGET,
      "mapping"),
    M("retarget_delta_rest_untransposed", "mapping/retarget/retarget.py",
      "D = stack_dot(self.P[bone][:, :3, :3], self.skel.rest_of(bone)[:3, :3].T @ C.T)",
      "D = stack_dot(self.P[bone][:, :3, :3], self.skel.rest_of(bone)[:3, :3] @ C.T)", RETARGET,
      "mapping"),
    M("retarget_slide_upright", "mapping/retarget/retarget.py",
      "    axis = _unit(lean_b)\n", "    axis = np.array([0.0, 0.0, 1.0])\n", RETARGET,
      "mapping"),
    M("retarget_channels_location_in_own_frame", "mapping/retarget/retarget.py",
      "    if far:       # Blender", "    if False:       # Blender", RETARGET, "mapping"),
    M("retarget_channels_quaternion_sign_jumps", "mapping/retarget/retarget.py",
      "    return loc, np.swapaxes(quat_continuous(np.swapaxes(q, 0, 1)), 0, 1)",
      "    return loc, q", RETARGET, "mapping"),
    M("retarget_control_location_never_keyed", "mapping/retarget/retarget.py",
      "                  c.parent is None or c.location) for c in bm.controls]",
      "                  c.parent is None) for c in bm.controls]", RETARGET, "mapping"),
    M("leg_twist_reversed", "mapping/sports/skier.py",
      "twist = {s: np.clip(-o.leg_twist_gain * (tilts[s] - th)",
      "twist = {s: np.clip(o.leg_twist_gain * (tilts[s] - th)", MAPPING, "mapping"),
    M("ski_tilt_halved", "mapping/sports/skier.py",
      "base = tilt_gain(traj, o.tilt_gain) * traj.C_f",
      "base = 0.5 * tilt_gain(traj, o.tilt_gain) * traj.C_f", MAPPING, "mapping"),
    M("outside_ski_swapped", "mapping/sports/skier.py",
      "outside_is_right = traj.C_f > 0", "outside_is_right = traj.C_f < 0", MAPPING, "mapping"),
    M("upper_twist_sign", "mapping/sports/skier.py",
      "twist_upper_body(b, up, -o.twist_amp * np.sin(traj.phi + o.twist_phase))",
      "twist_upper_body(b, up, o.twist_amp * np.sin(traj.phi + o.twist_phase))", MAPPING,
      "mapping"),
    M("spring_sign", "mapping/sports/snow.py",
      "return np.clip(static - (bridged_force(traj, span) - static_force(traj)) / k_s, lo, hi)",
      "return np.clip(static + (bridged_force(traj, span) - static_force(traj)) / k_s, lo, hi)",
      MAPPING, "mapping"),
    M("spring_unbridged", "mapping/sports/snow.py",
      "    if span <= 0.0 or len(s) < 2 or s[-1] <= s[0]:",
      "    if True:", SKIER_MAPPING, "mapping"),
    M("lean_sign", "mapping/sports/common.py",
      "add_local_rotation(b, B.LEAN, (0.0, 1.0, 0.0), -np.asarray(theta_v, float))",
      "add_local_rotation(b, B.LEAN, (0.0, 1.0, 0.0), np.asarray(theta_v, float))", MAPPING,
      "mapping"),
    M("object_heading_offset", "mapping/surface.py",
      "yaw = np.asarray(traj.theta_dir, float) - math.pi / 2",
      "yaw = np.asarray(traj.theta_dir, float)", MAPPING, "mapping"),
    M("crank_not_geared", "mapping/sports/cyclist.py",
      "crank_angle = wheel_angle / o.gear_ratio", "crank_angle = wheel_angle", MAPPING, "mapping"),
    M("steer_no_lean", "mapping/sports/cyclist.py",
      "return np.clip(np.arctan2(k * np.cos(theta_v),", "return np.clip(np.arctan2(k,",
      MAPPING, "mapping"),
    # -- the registries (docs/registry.md) ------------------------------------------------------
    M("rig_ignores_the_records_file", "mapping/rig_spec.py",
      "return _load_rig_file(str(SPORTS[name].rig_path(RIGS_DIR)))",
      'return _load_rig_file(str(RIGS_DIR / f"{name}.json"))', REGISTRY, "registry"),
    M("view_ignores_its_filter", "core/registry.py",
      "return (n for n, r in self._registry.items() if self._where(r))",
      "return iter(self._registry)", REGISTRY, "registry"),
    M("unregister_keeps_the_record", "core/registry.py",
      "        del self._records[name]\n", "", REGISTRY, "registry"),
    M("numbers_may_repeat", "core/registry.py",
      "if r.name != name and getattr(r, attr) == v), None)",
      "if False), None)", REGISTRY, "registry"),
    M("formation_reads_any_key", "crowd/reader.py",
      "    f.only(record.file_keys)\n", "", REGISTRY, "registry"),
    M("formation_refusal_unlabelled", "crowd/formations.py",
      "        raise FormationRefused(str(exc)) from None", "        raise", REGISTRY, "registry"),
    M("scene_preset_fixed_list", "core/course/scene.py",
      'fig = preset(f.string("preset", choices=tuple(PRESETS)))',
      'fig = preset(f.string("preset", choices=("skier", "snowboarder", "telemark", "cyclist")))',
      REGISTRY, "registry"),
    M("enum_items_never_rebuilt", "blender/registry_items.py",
      "key = (kind, registry.version)", "key = (kind, 0)", BLENDER_REGISTRY, "bake"),
    M("sport_enum_static", "blender/props/figure.py",
      "items=sport_items, default=0, options=_STATIC,",
      "items=sport_items(), default=0, options=_STATIC,", BLENDER_REGISTRY, "bake"),
    # -- bake (Blender; the bpy wheel) ---------------------------------------------------------
    M("nan_track_baked", "blender/anim/bake.py",
      "if not all(np.all(np.isfinite(a)) for a in arrays):", "if False:", BAKE, "bake"),
    M("clear_bake_drops_user_keys", "blender/anim/bake.py",
      "if has_user or bag is None or len(bag.fcurves) == 0:", "if True:", BAKE, "bake"),
    M("bake_drops_keyed_params", "blender/anim/bake.py",
      "params = [fc for fc in (bag.fcurves if bag else ())", "params = [fc for fc in ()",
      BAKE, "bake"),
    M("rebake_ignores_start", "blender/jobs/bake_job.py",
      "start = start_from_object(fig) if bake.figure_action(fig) is None else None",
      "start = start_from_object(fig)", BAKE, "bake"),
    M("rebake_removes_all_curves", "blender/anim/bake.py",
      "for fc in [fc for fc in bag.fcurves if fc.data_path in paths]:",
      "for fc in list(bag.fcurves):", BAKE, "bake"),
    # -- the bake's layers: tweaks above the bake (docs/layers.md) --------------------------------
    M("tweaks_replace_the_bake", "blender/anim/bake_layers.py",
      'adt.action_blend_type = "COMBINE"', 'adt.action_blend_type = "REPLACE"', LAYERS, "bake"),
    M("edited_bake_layer_rebaked", "blender/anim/bake_layers.py",
      "    if edited:\n", "    if False:\n", LAYERS, "bake"),
    M("clear_bake_deletes_tweaks", "blender/anim/bake_layers.py",
      "    if left == 0:\n", "    if True:\n", LAYERS, "bake"),
    M("rebake_makes_new_tweaks", "blender/anim/bake_layers.py",
      "    if action is None:\n        action = compat.assign_new_action",
      "    if True:\n        action = compat.assign_new_action", LAYERS, "bake"),
    # -- poles that plant (Section 7) -------------------------------------------------------------
    M("pole_lands_at_speed", "mapping/sports/skier.py",
      "            _approach(place, d, swing * APPROACH,",
      "            0 and _approach(place, d, swing * APPROACH,", SKIER_MAPPING, "mapping"),
    M("pole_comes_down_skimming_the_snow", "mapping/sports/skier.py",
      "STEEP, RISE = 1.0, 0.10", "STEEP, RISE = 0.0, 0.10", SKIER_MAPPING, "mapping"),
    M("pole_hole_from_the_trailing_swing", "mapping/sports/skier.py",
      "grip + length * _free_axis(grip, w, *swing[1:])", "grip + length * _free_axis(grip, *swing)",
      SKIER_MAPPING, "mapping"),
    M("pole_free_tip_left_under_the_snow", "mapping/sports/skier.py",
      "            free_tip = ~plan.planted", "            free_tip = plan.planted & False",
      SKIER_MAPPING, "mapping"),
    M("pole_planted_tip_lifted_off_its_hole", "mapping/sports/skier.py",
      "            free_tip = ~plan.planted", "            free_tip = ~plan.planted | True",
      POLES, "bake"),
    M("pole_aims_forward_after_plant", "mapping/sports/skier.py",
      "w_aim = np.where(d > 0.0, 0.0, w)", "w_aim = w", POLES, "bake"),
    M("users_pole_follows_the_hand", "mapping/retarget/retarget.py",
      "            rot[c] = S @ turn @ turned[c]\n", "",
      POLES, "bake"),
    M("users_hand_swings_the_builtins_reach", "mapping/sports/skier.py",
      "neutral, planted = (o.plant_reach * (", "neutral, planted = (1.0 * (", POLES, "bake"),
    M("users_pole_turns_about_the_wrist", "mapping/retarget/retarget.py",
      "    if not short.any():\n        return wrist, S", "    if True:\n        return wrist, S",
      RETARGET, "mapping"),
    M("planted_grip_only_towards_the_free_swing", "mapping/kinematics.py",
      "    cos = np.clip(cos0, np.maximum(near, -1.0), np.clip(far, -1.0, 1.0))",
      "    cos = cos0", RETARGET + SKIER_MAPPING, "mapping"),
    M("planted_hand_at_the_armpit", "mapping/sports/skier.py",
      "                              shoulder[idx], *reach)",
      "                              shoulder[idx], 0.0, reach[1])", SKIER_MAPPING, "mapping"),
    # -- crowd staging (docs/crowds.md) -----------------------------------------------------------
    M("staging_always_waits", "crowd/staging.py",
      '    along = staging == "along_track"\n', "    along = False\n", STAGING),
    M("staging_ahead_of_the_leader", "crowd/staging.py",
      "float) - back * d", "float) + back * d", STAGING),
    M("staging_keeps_the_offset", "crowd/staging.py",
      "float(pos[1])),\n                           time_offset=leader.time_offset))",
      "float(pos[1])),\n                           time_offset=m.time_offset))", STAGING),
    M("staging_path_follower_keeps_the_offset", "crowd/staging.py",
      "_led_in(m.controller, back),\n                               time_offset=leader.",
      "_led_in(m.controller, back),\n                               time_offset=m.", STAGING),
    M("staging_path_follower_waits", "crowd/staging.py",
      "        if m.is_path:\n            out.append(replace(m, controller=_led_in(",
      "        if m.is_path:\n            out.append(m)\n            continue\n"
      "            out.append(replace(m, controller=_led_in(", STAGING),
    M("staging_path_lead_in_kept_at_the_start", "crowd/staging.py",
      "    state0[:2] = path.knots[0]\n", "", STAGING),
    M("staging_path_runs_to_the_end", "crowd/staging.py",
      "path = sc.path.led_in(back).split(sc.path.length())[0]", "path = sc.path.led_in(back)",
      STAGING),
    M("staging_waiting_path_past_its_start", "crowd/staging.py",
      "            if back >= total:\n", "            if False:\n", STAGING),
    M("staging_waiting_path_runs_to_the_end", "crowd/staging.py",
      "            out.append(cut_short(m, back))", "            out.append(m)", STAGING),
    M("path_lead_in_ahead", "core/course/path.py",
      "np.vstack([self.knots[0] - d, self.knots])", "np.vstack([self.knots[0] + d, self.knots])",
      [T + "test_path.py"]),
    M("path_split_before_tangent_whole", "core/course/path.py",
      "np.vstack([self.t_out[:seg], 3.0 * (a[0] - k0)])",
      "np.vstack([self.t_out[:seg], self.t_out[seg]])", [T + "test_path.py"]),
    M("peloton_rows_ride_to_the_end", "crowd/formations.py",
      "out.append(cut_short(rider, row * gap))", "out.append(rider)", [T + "test_crowd.py"]),
    M("add_crowd_path_followers_not_staged", "blender/ops/crowd.py",
      "        return stage(lead, members, heading, v.staging.lower())",
      "        return members if lead.is_path else stage(lead, members, heading, "
      "v.staging.lower())", [T + "test_blender_crowd_staging.py"], "bake"),
    # -- formations made from a template, followed with a path (docs/crowds.md) ----------------
    M("add_crowd_template_left_standing", "blender/ops/crowd.py",
      "            crowd_scene.set_aside(template)\n", "            pass\n",
      [T + "test_blender_crowd_path_formations.py"], "bake"),
    M("set_aside_leaves_the_body", "blender/scene/crowd_scene.py",
      "    for obj in [template, *template.children_recursive,",
      "    for obj in [template, *(),", [T + "test_blender_crowd_path_formations.py"], "bake"),
    M("synchronized_turns_only", "crowd/formations.py",
      'name="synchronized", label="Synchronized", number=1, template="any",',
      'name="synchronized", label="Synchronized", number=1, template="turns",',
      [T + "test_blender_crowd_path_formations.py"], "bake"),
    # -- Follow Path on a Ground mesh -------------------------------------------------
    M("follow_ground_is_an_obstacle", "blender/scene/follow_scene.py",
      "(s.foot_track, s.path, s.ground)", "(s.foot_track, s.path)", FOLLOW_GROUND, "bake"),
    M("follow_ground_obstacles_dropped", "blender/scene/follow_scene.py",
      "job = FollowJob(figure, control, footprints,", "job = FollowJob(figure, control, [],",
      FOLLOW_GROUND, "bake"),
    M("follow_ground_planned_flat", "blender/scene/follow_ground.py",
      'terrain = {"ground": ground.field,', 'terrain = {"ground": None,',
      FOLLOW_GROUND, "bake"),
    M("follow_ground_start_speed_current", "blender/scene/follow_ground.py",
      'V0 = float(sampled_setting(fig, "speed", first)[0])', "V0 = float(fig.turning.speed)",
      FOLLOW_GROUND, "bake"),
    M("follow_ground_upright", "blender/scene/follow_scene.py",
      "normal=surface_normals(traj, ground), surface", "normal=None, surface", FOLLOW_GROUND,
      "bake"),
    M("follow_ground_track_flat", "blender/anim/figure_bake.py",
      "traj.y, z=traj.z,", "traj.y, z=None,", FOLLOW_GROUND, "bake"),
    M("follow_ground_any_mesh", "blender/scene/follow_ground.py",
      "    check_height_field(obj, depsgraph, ground)\n", "", FOLLOW_GROUND, "bake"),
    M("follow_ground_path_anywhere", "blender/scene/follow_ground.py",
      "off = np.flatnonzero(~over_mesh(ground, xy))", "off = np.flatnonzero(xy[:, 0] != xy[:, 0])",
      FOLLOW_GROUND, "bake"),
    # -- what the model changed, said (the bake's lean, Follow Path's distance from the path) --
    # -- race-grade carving (core/equipment.py, the steering room, docs/racing.md) ------------
    M("sidecut_edge_complement", "core/equipment.py",
      "out = np.sign(c) * np.arccos(cos)", "out = np.sign(c) * (0.5 * np.pi - np.arccos(cos))",
      RACING),
    M("carving_limit_without_edge", "core/equipment.py",
      "return 1.0 / (self.sidecut_radius * math.cos(self.edge_max))",
      "return 1.0 / self.sidecut_radius", RACING),
    M("edge_limit_lean_unsigned", "core/equipment.py",
      "np.sign(C_f) * theta_v + self.angulation", "np.abs(theta_v) + self.angulation",
      (T + "test_planner_edge_limit.py",)),
    M("edge_limit_not_clipped", "core/planner/problem.py",
      "fell |= ~self.edge_limit.holds(P[:, THETA_V], C).all(axis=0)", "pass",
      (T + "test_planner_edge_limit.py",)),
    M("q_near_ignored", "core/planner/problem.py",
      "if st.q_near and st.q_near != st.q and (len(p.obstacles) or p.movers is not None):",
      "if False:", (T + "test_planner_choices_near.py",)),
    # -- the racer's line (core/planner/reach.py) and the leg-force limit ----------------------
    M("race_bound_interval_ignored", "core/planner/reach.py",
      "% (2 * np.pi) - np.pi) - 0.5 * (hi - lo)", "% (2 * np.pi) - np.pi)",
      (T + "test_planner_race.py",)),
    M("race_cost_half_speed", "core/planner/reach.py",
      "self.step = problem.speed.max * st.dt", "self.step = 0.5 * problem.speed.max * st.dt",
      (T + "test_planner_race.py",)),
    M("race_direction_mirrored", "core/planner/reach.py",
      "self.angle = float(np.arctan2(self.e[1], self.e[0]))",
      "self.angle = float(np.arctan2(-self.e[1], self.e[0]))", (T + "test_planner_race.py",)),
    M("race_search_takes_the_path_bound", "core/planner/search.py",
      "    if problem.race is not None:      # the racer's line", "    if False:",
      (T + "test_planner_race.py",)),
    M("race_scene_line_ignored", "core/course/scene.py",
      '"line": pl.string("line", "path", choices=LINES),', "",
      (T + "test_planner_race.py",)),
    M("leg_force_not_clipped", "core/planner/problem.py",
      "fell |= ~(self.leg_force_bw(P, C) <= st.leg_force_max).all(axis=0)", "pass",
      (T + "test_planner_race.py",)),
    # -- the racer's line with the speed free (RaceCost's envelope, bound, leg force) ---------
    M("race_free_envelope_no_gravity", "core/planner/reach.py",
      "self.accel = problem.body.g * problem._sin_max if self.free else 0.0",
      "self.accel = 0.0", (T + "test_planner_race_slope.py",)),
    M("race_free_envelope_no_lean", "core/planner/reach.py",
      "out.root = (float(t), float(state[V_CM]), 2.0 * max(lean, 0.0))",
      "out.root = (float(t), float(state[V_CM]), 0.0)", (T + "test_planner_race_slope.py",)),
    M("race_free_cost_speed_held", "core/planner/reach.py",
      "short = np.maximum(self.envelope(self.root, t) - P[:, V_CM] * c, 0.0)",
      "short = np.maximum(self.envelope(self.root, t) - self.root[1] * c, 0.0)",
      (T + "test_planner_race_slope.py",)),
    M("race_free_bound_fast_end_only", "core/planner/reach.py",
      "r_lo = np.where(c_lo > 0.0, k_lo, k_hi) * c_lo / (1.0 + c_lo * b.l * sl)",
      "r_lo = k_hi * c_lo / (1.0 + c_lo * b.l * sl)", (T + "test_planner_race_slope.py",)),
    M("race_free_bound_no_heading_gain", "core/planner/reach.py",
      "speeds=(MIN_SPEED, top), gains=(cos, 1.0 / cos))",
      "speeds=(MIN_SPEED, top))", (T + "test_planner_race_slope.py",)),
    M("race_free_leg_force_held_speed", "core/planner/terrain_problem.py",
      "F = model.leg_force(p.body, S[THETA_V], S[4], alpha, cf, S[V_CM], V_f, fr)[0]",
      "F = model.leg_force(p.body, S[THETA_V], S[4], alpha, cf, p.V0, V_f, fr)[0]",
      (T + "test_planner_race_slope.py",)),
    M("race_braking_capped_by_the_line", "core/course/follow_problem.py",
      "cap = replace(cap, curvature=0.0 if race else path_curvature_max(self.path),",
      "cap = replace(cap, curvature=path_curvature_max(self.path),",
      (T + "test_planner_race_slope.py",)),
    M("reid_com_outside_the_foot", "core/course/reid.py",
      "    y = traj.y + off * np.cos(traj.theta_dir)", "    y = traj.y - off * np.cos(traj.theta_dir)",
      (T + "test_reid_courses.py",)),
    M("reid_entry_and_exit_turns_kept", "core/course/reid.py",
      "if skip <= k < len(gate_x) - skip]", "if 0 <= k < len(gate_x)]",
      (T + "test_reid_courses.py",)),
    M("reid_turn_of_two_gates", "core/course/reid.py",
      "        if len(inside) == 1:", "        if len(inside):", (T + "test_reid_courses.py",)),
    M("reid_radius_of_the_centre_of_mass", "core/course/reid.py",
      '(("radius", "R_foot", R), ("edge", "edge", edge))',
      '(("radius", "R_com", R), ("edge", "edge", edge))', (T + "test_reid_courses.py",)),
    M("racer_skis_linear_tilt", "mapping/sports/skier.py",
      "        edge = carving.edge_angle(traj.C_f)\n        return {s: edge for s, _ in SIDES}\n",
      "        pass\n", RACING, "mapping"),
    M("angulation_com_uncorrected", "mapping/sports/snow.py",
      "        extra = extra + step\n", "        pass\n", SNOW_COM, "mapping"),
    M("angulation_com_no_secant", "mapping/sports/snow.py",
      "        if last is not None:\n", "        if False:\n", SNOW_COM, "mapping"),
    M("com_model_no_slide", "mapping/sports/snow.py",
      "out = ankle_z * (1.0 / np.cos(legs_lean + d) - secant)", "out = 0.0 * ankle_z", SNOW_COM,
      "mapping"),
    M("com_model_legs_unturned", "mapping/sports/snow.py",
      'LEG_SEGMENTS = ("thigh", "leg", "foot")', "LEG_SEGMENTS = ()", SNOW_COM, "mapping"),
    M("com_one_trial_pose", "mapping/sports/snow.py",
      "COM_PASSES = 2\n", "COM_PASSES = 1\n", SNOW_COM, "mapping"),
    M("angulation_back_unsigned", "mapping/sports/snow.py",
      "return np.sign(th) * np.minimum(", "return np.abs(th) * 0.0 + np.minimum(", RACING,
      "mapping"),
    M("angulation_upper_body_leans", "mapping/sports/skier.py",
      "add_local_rotation(b, B.HIPS, fwd, back + extra)", "add_local_rotation(b, B.HIPS, fwd, extra)",
      RACING, "mapping"),
    M("angulation_shins_along_the_legs", "mapping/sports/skier.py",
      "np.where(tilts[s] * th > th * th, tilts[s], th)", "th", RACING, "mapping"),
    M("shank_twist_far_root", "mapping/sports/skier.py",
      "return np.where(np.abs(a) <= np.abs(c), a, c)", "return np.where(np.abs(a) <= np.abs(c), c, a)",
      RACING, "mapping"),
    M("ankle_at_its_rest_height", "mapping/sports/skier.py",
      "z = height_on_ground(b, spec, ski, R, a_rest)", "z = a_rest[2]", RACING, "mapping"),
    M("carver_board_linear_tilt", "mapping/sports/snowboarder.py",
      'carving = carving_of(traj.meta.get("preset"))', "carving = None", RACING, "mapping"),
    M("carver_com_uncorrected", "mapping/sports/snowboarder.py",
      "builder, traj, o, spec, tilt, back, extra), passes)",
      "builder, traj, o, spec, tilt, back, 0.0 * extra), passes)", RACING, "mapping"),
    M("carver_com_two_passes", "mapping/sports/snowboarder.py",
      "CARVER_PASSES = 3", "CARVER_PASSES = 2", RACING, "mapping"),
    M("snowboarder_com_uncorrected", "mapping/sports/snowboarder.py",
      "back, passes = np.zeros(len(traj)), COM_PASSES", "back, passes = np.zeros(len(traj)), 0",
      MAPPING, "mapping"),
    M("carver_upper_body_leans", "mapping/sports/snowboarder.py",
      "add_local_rotation(b, B.HIPS, (0.0, 1.0, 0.0), back + extra)",
      "add_local_rotation(b, B.HIPS, (0.0, 1.0, 0.0), extra)", RACING, "mapping"),
    M("preset_resistance_not_its_sports", "core/physics/model.py",
      'RESISTANCE = ChainView(SPORTS.view("resistance"), SPORT_PRESETS.view("resistance"))',
      'RESISTANCE = SPORTS.view("resistance")', RACING),
    M("steer_room_fixed_share", "core/controllers/feasible.py",
      "[self.max_lean(omega0 / b) / b for b in betas])", "[0.85 * self.max_lean(omega0)])",
      LEAN_ROOM),
    M("steer_room_ignores_modified_half_turns", "core/controllers/feasible.py",
      "[self.max_lean(omega0 / b) / b for b in betas])", "[self.max_lean(omega0) for b in betas])",
      LEAN_ROOM),
    M("steerable_leans_frequency_inverted", "core/controllers/feasible.py",
      "out = np.minimum(out, self.max_leans(w / b) / b)",
      "out = np.minimum(out, self.max_leans(w * b) / b)", LEAN_ROOM),
    M("braking_keeps_the_held_heading_room", "core/controllers/braking.py",
      "        controller.steer_betas = BRAKE_BETAS\n", "", [T + "test_braking.py"]),
    M("lean_input_stops_at_60", "core/ranges.py",
      '"theta_max": Range(1 * _DEG, 85 * _DEG,', '"theta_max": Range(1 * _DEG, 60 * _DEG,',
      [T + "test_lean_range.py"]),
    # -- one lean range per figure, and the run's lean report -------------------------------
    M("lean_range_reaches_the_fall", "core/ranges.py",
      "hi=theta_fall, hi_open=True, explain=True,",
      "hi=theta_fall, hi_open=False, explain=True,", LEAN_RANGE),
    M("lean_error_without_reason", "core/validate.py",
      'why = f": {rng.reason}" if rng.explain else ""', 'why = ""', LEAN_RANGE),
    M("cli_lean_global_range", "cli/simulate.py",
      "                                  leans, deg=True))",
      '                                  "theta_max", deg=True))', LEAN_RANGE),
    M("schedule_lean_global_range", "core/controllers/schedule.py",
      'rng = lean if name == "lean_deg" and lean is not None else RANGES[_COLUMNS[name]]',
      "rng = RANGES[_COLUMNS[name]]", LEAN_RANGE),
    M("crowd_lean_global_range", "crowd/reader.py",
      'math.radians(t.number("lean_deg", leans.deg())),',
      'math.radians(t.number("lean_deg", RANGES["theta_max"].deg())),', LEAN_RANGE),
    M("render_job_lean_global_range", "blender/render/config.py",
      '    lean = lean_range(SPORTS[sport].figure.limits.theta_fall, f"the {sport}").deg()',
      '    lean = RANGES["theta_max"].deg()', [T + "test_render_job_config.py"]),
    M("report_keeps_the_first_turn", "core/controllers/ellipse.py",
      "        if last is None or replace(last, t=t) != turn:", "        if last is None:",
      LEAN_REPORT),
    M("report_without_the_other_turn", "core/controllers/feasible.py",
      "other = followed[-1] if followed[-1] is not worst else followed[0]",
      "other = followed[0]", LEAN_REPORT),
    M("report_names_the_turn_s_own_bound", "core/controllers/ellipse.py",
      "beta = steer[0] if steer and tmf < f.max_lean(w) * (1 - 1e-12) else 1.0",
      "beta = 1.0", LEAN_REPORT),
    M("report_names_the_first_steering_beta", "core/controllers/ellipse.py",
      "beta = steer[0] if steer and tmf < f.max_lean(w) * (1 - 1e-12) else 1.0",
      "beta = self.steer_betas[0] if steer and tmf < f.max_lean(w) * (1 - 1e-12) else 1.0",
      LEAN_REPORT),
    M("bake_lean_range_global", "blender/scene/scene_adapters.py",
      '    leans = lean_range(figure.limits.theta_fall, f"the {figure.name}")',
      '    leans = RANGES["theta_max"]', NOTES, "bake"),
    M("bake_note_drops_the_grip", "blender/jobs/model_notes.py",
      '    notes = [traj.meta.get("grip_limited", "")] + \\', "    notes = [] + \\", NOTES,
      "bake"),
    M("panel_drops_the_steering_line", "blender/jobs/model_notes.py",
      "    if turn.beta != 1.0:\n        lines.append(", "    if False:\n        lines.append(",
      NOTES, "bake"),
    M("commanded_turn_unlimited", "core/controllers/ellipse.py",
      "return self._turn(t, w, tm, self.feasible_lean(w, tm))", "return self._turn(t, w, tm, tm)",
      [T + "test_feasible_turns.py"]),
    M("deviation_nearest_not_farthest", "core/course/path.py",
      "    k = int(np.argmax(d))", "    k = int(np.argmin(d))", [T + "test_path.py"]),
    M("deviation_along_from_start", "core/course/path.py",
      "float(arc[j]))", "float(arc[-1] - arc[j]))", [T + "test_path.py"]),
    M("bake_lean_note_dropped", "blender/jobs/pipeline.py",
      "        traj = with_turn(traj, controller)", "        pass", NOTES, "bake"),
    M("follow_warns_never", "blender/jobs/model_notes.py",
      "    if dev.distance > warn:", "    if False:", NOTES, "bake"),
    M("follow_frame_not_offset", "blender/jobs/model_notes.py",
      "frame = frame_start + round(dev.t * fps)", "frame = round(dev.t * fps)", NOTES, "bake"),
    M("fall_report_names_no_setting", "blender/scene/figure_context.py",
      "        msg = in_settings(str(exc))", "        msg = str(exc)", NOTES, "bake"),
    M("panel_names_the_core_bound", "blender/jobs/model_notes.py",
      "limited by {setting}\"]", "limited by {turn.bound}\"]", NOTES, "bake"),
    # -- the export-ready bake ---------------------------------------------------------------
    M("gltf_keeps_other_bakes", "blender/anim/export_gltf.py",
      "    return owner is not None and owner != obj", "    return False", EXPORT, "bake"),
    M("fbx_take_not_keyed", "blender/anim/export_ready.py",
      "    bake.write_channels(bag, [(path, 0,", "    0 and bake.write_channels(bag, [(path, 0,",
      EXPORT, "bake"),
    M("fbx_figure_take_dropped", "blender/anim/figure_bake.py",
      "        track = export_ready_mod.with_take(fig, track)", "        pass",
      EXPORT + [T + "test_blender_physics.py"], "bake"),
    M("fbx_bake_take_fits_its_figure", "blender/anim/bake.py",
      "        elif prop not in obj.keys():", "        if prop not in obj.keys():", EXPORT,
      "bake"),
    M("fbx_tweak_take_one_frame", "blender/anim/bake.py",
      "    bake_layers.span_tweaks(obj, action.frame_range)", "    pass", EXPORT, "bake"),
    M("state_not_driven", "blender/anim/export_state.py",
      '        _drive(emp, "location", 0, fig, prop, 1.0)', "        pass", EXPORT, "bake"),
    M("state_not_keyed_for_gltf", "blender/anim/export_state.py",
      "        key_in_place(fig, emp, frames)", "        pass", EXPORT, "bake"),
    M("state_dropped_by_follow_path", "blender/anim/figure_bake.py",
      "            export_turn_state = carried",
      "            export_turn_state = False", EXPORT, "bake"),
    M("state_kept_by_clear_bake", "blender/ops/bake.py",
      "            export_state.clear_state(fig)", "            pass", EXPORT, "bake"),
    M("gltf_tweaks_sampled_without_the_bake", "blender/anim/export_gltf.py",
      "                self.tweaks.get(blender_object.name) == blender_action",
      "                False", EXPORT, "bake"),
    M("gltf_bake_bones_over_the_tweaks", "blender/anim/export_gltf.py",
      "[c for c in channels if id(c.target.node) not in bones",
      "[c for c in channels if True", EXPORT, "bake"),
    M("gltf_other_figures_tweaks_kept", "blender/anim/export_gltf.py",
      "    return bake_layers.TWEAKS_OF not in action or action == tweaks", "    return True",
      EXPORT, "bake"),
    M("gltf_tweaks_short_of_the_bake_sampled", "blender/anim/export_gltf.py",
      "    return tweaks if lo <= start and hi >= end else None", "    return tweaks", EXPORT,
      "bake"),
    M("fbx_tweaks_not_flattened", "blender/anim/export_fbx.py",
      "            _flatten(fig, scene, undo)", "            pass", EXPORT, "bake"),
    M("fbx_tweak_layers_keep_their_takes", "blender/anim/export_fbx.py",
      "            undo.append(_fit_nothing(action))", "            pass", EXPORT, "bake"),
    M("fbx_strip_keeps_the_flattened_action", "blender/anim/export_fbx.py",
      "        if strip.action != baked:", "        if False:", EXPORT, "bake"),
    M("fbx_tweak_layer_left_unassigned", "blender/anim/export_fbx.py",
      "        compat.restore_action(fig, tweaks, tweak_slot)", "        pass", EXPORT, "bake"),
    M("gltf_shared_bake_not_copied", "blender/anim/export_gltf.py",
      "    export_shared.own_copies(list(bpy.context.scene.objects))", "    pass", EXPORT, "bake"),
    M("gltf_failed_export_no_timer", "blender/anim/export_gltf.py",
      "        bpy.app.timers.register(restore_after_export, first_interval=0.0)", "        pass",
      EXPORT, "bake"),
    M("gltf_failed_export_saved", "blender/ops/export.py",
      "    bpy.app.handlers.save_pre.append(export_gltf.restore_before_save)", "    pass", EXPORT,
      "bake"),
    M("export_copy_not_shifted", "blender/anim/export_shared.py",
      "    _shift_keys(copy, shift)", "    _shift_keys(copy, 0.0)", EXPORT, "bake"),
    M("export_copy_keeps_its_frame_range", "blender/anim/export_shared.py",
      "    copy.use_frame_range = True", "    pass", EXPORT, "bake"),
    M("export_pieces_merge_into_the_shared_bake", "blender/anim/export_shared.py",
      "            action[bake.MERGE_INTO] = into", "            pass", EXPORT, "bake"),
    M("bake_not_held_from_the_scene_start", "blender/anim/bake.py",
      "    return float(min(first, start))", "    return float(first)", EXPORT, "bake"),
    M("export_copy_left_behind", "blender/anim/export_shared.py",
      "        bpy.data.actions.remove(copy)", "        pass", EXPORT, "bake"),
    M("fbx_tweaks_shared_not_copied", "blender/ops/export.py",
      "with export_shared.unshared(list(objs)), export_fbx", "with export_fbx", EXPORT, "bake"),
    M("equipment_keyed_where_it_stands", "blender/anim/export_ready.py",
      "    obj[KEYED] = [float(v) for row in obj.matrix_basis for v in row]\n",
      "    obj[KEYED] = [float(v) for row in obj.matrix_basis for v in row]\n"
      "    obj.matrix_basis = obj.matrix_world\n", EXPORT, "bake"),
    M("terrain_tiles_own_normals", "blender/render/terrain.py",
      "            mesh.normals_split_custom_set_from_vertices(", "            (lambda _: None)(",
      [T + "test_blender_ground.py"], "bake"),
]

LIVE_MUTANTS = [
    # -- Live Preview ---------------------------------------------------------------------------
    M("live_keys_by_value", "blender/jobs/live.py",
      "            if fc is not None:           # keyed: the curve is what the bake reads",
      "            if False:", LIVE, "live"),
    M("live_rewrite_keeps_old_values", "blender/anim/bake.py",
      "        buf[2 * i0 + 1:2 * (i0 + n):2] = -values if signs.get(path, 0.0) < 0 else values\n",
      "", LIVE, "live"),
    M("live_failure_forgotten", "blender/jobs/live.py",
      "failure = FAILURES[fig.name] = Failure(", "failure = Failure(", LIVE, "live"),
    M("live_fall_frame_from_zero", "blender/jobs/live.py",
      "frame = frames.start + int(round(exc.t * frames.fps))",
      "frame = int(round(exc.t * frames.fps))", LIVE, "live"),
    M("live_window_quaternion_sign", "blender/anim/bake.py",
      "-values if signs.get(path, 0.0) < 0 else values", "values", LIVE, "live"),
    M("live_window_marks_done", "blender/jobs/live.py",
      "                _WINDOWS[fig.name] = key\n",
      "                _WINDOWS[fig.name] = key\n                bake.figure_action(fig)[KEY] = key\n",
      LIVE, "live"),
    M("live_own_track_an_obstacle", "blender/jobs/live.py",
      "if o not in own and figure_settings(o.parent or o) is None:",
      "if figure_settings(o.parent or o) is None:", LIVE, "live"),
    M("live_wheels_from_part", "mapping/sports/cyclist.py",
      'float(traj.meta.get("s_start", traj.s[0]))', "float(traj.s[0])", LIVE, "live"),
    M("live_body_step_builds_tables", "blender/jobs/live.py",
      "with nearby_tables(NEARBY_BODY):", "with nearby_tables(0.0):", LIVE, "live"),
    M("live_ground_step_exact", "blender/jobs/live.py",
      "coarse_dt=coarse, stride=PREVIEW_STRIDE, skip=skip)", "coarse_dt=coarse, skip=skip)",
      LIVE, "live"),
    M("live_ground_stride_dropped", "blender/jobs/pipeline.py",
      "stride = stride if target is None and skidding is None else 1", "stride = 1", LIVE,
      "live"),
    M("live_window_part_from_the_first_frame", "blender/jobs/live.py",
      "    k = mlo - frames.start - skip\n", "    k = mlo - frames.start\n", LIVE, "live"),
    M("live_handlers_left", "blender/jobs/live.py",
      "        while fn in handlers:\n            handlers.remove(fn)", "        pass", LIVE, "live"),
    M("live_rig_wheels_from_the_context", "blender/scene/retarget_adapter.py",
      'distance=float(traj.meta.get("path_start", 0.0)))', "distance=0.0)", LIVE_RIG, "live"),
    M("live_rig_window_rows_shifted", "blender/jobs/live.py",
      "rows=(lo - mlo, hi - mlo + 1),", "rows=(lo - mlo + 1, hi - mlo + 2),", LIVE_RIG, "live"),
    M("live_drag_rig_blind_to_its_map", "blender/jobs/live.py",
      "key = (h.digest(), fig.turning.sport,", "key = (fig.turning.sport,", LIVE_RIG, "live"),
    M("live_drag_rig_kept_after_release", "blender/jobs/live.py",
      "        _RIGS.pop(fig.name, None)\n", "", LIVE_RIG, "live"),
    M("retarget_rest_kept_for_any_map", "mapping/retarget/retarget.py",
      "    key = (id(bm), id(bi.fit), sport, type(bi.skel).__name__)\n"
      "    kept = rig._at_rest.get(key)\n"
      "    if kept is not None and kept[0] is bm and kept[1] is bi.fit:",
      "    key = (sport, type(bi.skel).__name__)\n    kept = rig._at_rest.get(key)\n"
      "    if kept is not None:", RETARGET, "live"),
    M("live_release_keys_dropped", "blender/anim/bake.py",
      "    _WINDOW_KEYS[action.as_pointer()] = (action[bake_layers.FINGERPRINTS], keys, crcs)",
      "    if by_key:\n"
      "        _WINDOW_KEYS[action.as_pointer()] = (action[bake_layers.FINGERPRINTS], keys, crcs)",
      LIVE, "live"),
    M("live_crc_polynomial", "blender/anim/key_crc.py",
      "POLY = 0xEDB88320", "POLY = 0xEDB88321", KEY_CRC, "live"),
    M("live_crc_bits_for_bytes", "blender/anim/key_crc.py",
      "    for _ in range(3):                           # 2, 4, 8 bits: a byte",
      "    for _ in range(2):", KEY_CRC, "live"),
    M("live_crc_tail_short", "blender/anim/bake.py",
      "4 * 2 * (total - i0 - n)", "4 * 2 * (total - i0 - n - 1)", LIVE, "live"),
    M("live_crc_of_the_old_keys", "blender/anim/bake.py",
      "        after = np.stack([old[fc][window] for fc, _, _ in todo])",
      "        after = before", LIVE, "live"),
]
MUTANTS += LIVE_MUTANTS

SHARE = [T + "test_mapping_shared_motion.py", T + "test_blender_crowd_share.py",
         T + "test_blender_crowd.py"]
SHARE_MUTANTS = [
    # -- shared motion: which figures play another's bake, and that nothing changes another's -----
    M("share_one_key_apart_loosened", "mapping/shared_motion.py",
      "return bool(np.all(np.abs(a - b) <= np.spacing(_scale(a, b))))",
      "return bool(np.all(np.abs(a - b) <= 1e3 * np.spacing(_scale(a, b))))", SHARE, "share"),
    M("share_location_unchecked", "mapping/shared_motion.py",
      "return d if bool(np.all(np.abs(played - b) <= tol)) else None", "return d", SHARE, "share"),
    M("share_half_frames", "mapping/shared_motion.py",
      "if shift != round(shift) or \\", "if False or \\", SHARE, "share"),
    M("share_later_source", "mapping/shared_motion.py",
      "key=lambda i: (float(tracks[i].frames[0]), i))", "key=lambda i: i)", SHARE, "share"),
    M("share_strip_not_shifted", "blender/anim/bake.py",
      "    played.action_frame_start = since - shift    #",
      "    played.action_frame_start = since    #", SHARE, "share"),
    M("share_leader_rebakes_in_place", "blender/anim/bake.py",
      "    given_up = action is not None and shared_elsewhere(action)\n",
      "    given_up = False\n", SHARE, "share"),
    M("share_leader_live_in_place", "blender/anim/bake.py",
      "if bag is None or shared_elsewhere(action):", "if bag is None:", SHARE, "share"),
    M("share_leader_clear_deletes", "blender/anim/bake.py",
      "    if action is not None and shared_elsewhere(action):    # theirs to keep playing",
      "    if False:", SHARE, "share"),
    M("share_delta_left", "blender/anim/bake.py",
      "        obj.delta_location = (0.0, 0.0, 0.0)\n        del obj[SHARE_OFFSET]",
      "        del obj[SHARE_OFFSET]", SHARE, "share"),
    M("share_over_users_delta", "blender/anim/bake.py",
      "return (SHARE_OFFSET in obj or not any(obj.delta_location)) and \\",
      "return True and \\", SHARE, "share"),
]
MUTANTS += SHARE_MUTANTS

# -- a bake that stashes the user's action says so (Bake Turns and Follow Path) -----------------
MUTANTS += [
    M("stash_note_unsaid", "blender/anim/user_action.py",
      "    if user is None or user == before.get(fig.name):\n        return None",
      "    return None", [T + "test_blender_layers.py"], "bake"),
    M("stash_note_every_rebake", "blender/anim/user_action.py",
      "    if user is None or user == before.get(fig.name):", "    if user is None:",
      [T + "test_blender_layers.py"], "bake"),
]

# -- modules that had no mutant: the open-loop law (Section 4), the phase post-pass (Section 6.2),
# the paper's phase-ellipse law (Section 5.1), the fall table's monotonicity (Eq. 2), the free-speed
# planner's run-away bound (Eq. 21, docs/TERRAIN.md), the free-speed stepper -----------------
TERMS = [T + "test_mutation_guards_terms.py"]
OPEN_LOOP = TERMS + [T + "test_controllers.py", T + "test_one_figure.py"]
PHASE_EST = TERMS + [T + "test_phase_estimate.py"]
PAPER_LAW = TERMS + [T + "test_ellipse_law.py", T + "test_controllers.py"]
FALL_TABLE = TERMS + [T + "test_planner_fall_table.py", T + "test_mutation_guards_planner.py"]
FREE_PLAN = TERMS + [T + "test_planner_terrain.py"]
ANTHRO = TERMS + [T + "test_telemark_body.py"]
TELEMARK = [T + "test_mapping_telemark.py", T + "test_telemark_body.py"]
FREE_SIM = TERMS + [T + "test_terrain_sim.py", T + "test_energy.py", T + "test_speed_is_physics.py"]
PREVIEW = [T + "test_terrain_preview.py"]
MUTANTS += [
    M("open_loop_phase_frozen_in_step", "core/controllers/open_loop.py",
      "phi = self._phi + 0.5 * (self.omega0(self._t) + w) * tau", "phi = self._phi", OPEN_LOOP),
    M("open_loop_phase_left_rectangle", "core/controllers/open_loop.py",
      "self._phi += 0.5 * (self.omega0(self._t) + self.omega0(t)) * (t - self._t)",
      "self._phi += self.omega0(self._t) * (t - self._t)", OPEN_LOOP),
    M("phase_estimate_omega0_is_rate_intercept", "core/course/phase_estimate.py",
      "omega0 = wt / tm", "omega0 = wt", PHASE_EST),
    M("phase_estimate_crossing_at_sample", "core/course/phase_estimate.py",
      "w = y[i] / (y[i] - y[j])", "w = 0.0 * y[i]", PHASE_EST),
    M("phase_estimate_intercepts_swapped", "core/course/phase_estimate.py",
      "t_th, v_th = axis_crossings(t, om, th)", "t_th, v_th = axis_crossings(t, th, om)",
      PHASE_EST),
    M("paper_law_a13_sign", "core/controllers/ellipse_paper.py",
      "    a13 = -w13_sq * th\n", "    a13 = w13_sq * th\n", PAPER_LAW),
    M("paper_law_a24_no_ellipse_factor", "core/controllers/ellipse_paper.py",
      "a24 = -(omega0 * theta_max) ** 2 * (1.0 - x * x) / np.where",
      "a24 = -(omega0 * theta_max) ** 2 / np.where", PAPER_LAW),
    M("paper_law_one_a13_sign", "core/controllers/ellipse_paper.py",
      "        a = -w13_sq * th\n    else:", "        a = w13_sq * th\n    else:", PAPER_LAW),
    M("paper_law_one_a24_no_ellipse_factor", "core/controllers/ellipse_paper.py",
      "a = -(omega0 * theta_max) ** 2 * (1.0 - x * x) / th",
      "a = -(omega0 * theta_max) ** 2 / th", PAPER_LAW),
    M("fall_table_cooperative_sign", "core/planner/fall_table.py",
      "d = b.g * c - C * V * V * (C * b.l - s)", "d = b.g * c + C * V * V * (C * b.l - s)",
      FALL_TABLE),
    M("fall_table_cooperative_unsquared", "core/planner/fall_table.py",
      "/ (1.0 - C * b.l * s) ** 2", "/ (1.0 - C * b.l * s)", FALL_TABLE),
    M("fall_table_steers_the_other_way", "core/planner/fall_table.py",
      "u = np.full(m, lim.dC_f_max)", "u = np.full(m, -lim.dC_f_max)", FALL_TABLE),
    M("free_speed_limit_no_gravity", "core/planner/terrain_problem.py",
      "return (V_root + p.body.g * p._sin_max * T) / (1.0 - p._slip)",
      "return (V_root) / (1.0 - p._slip)", FREE_PLAN),
    M("free_speed_limit_no_eq21", "core/planner/terrain_problem.py",
      "return (V_root + p.body.g * p._sin_max * T) / (1.0 - p._slip)",
      "return (V_root + p.body.g * p._sin_max * T)", FREE_PLAN),
    M("free_steepest_plane_tangent", "core/planner/terrain_problem.py",
      "return math.sin(ground.slope)", "return math.tan(ground.slope)", FREE_PLAN),
    M("free_brake_at_body_speed", "core/planner/terrain_problem.py",
      "d = d[:5] + (d[5] - b * V_f / x[V_CM],)", "d = d[:5] + (d[5] - b,)",
      FREE_PLAN + [T + "test_planner_speed_cap.py"]),
    M("free_sim_s_at_body_speed", "core/physics/terrain_sim.py",
      "ds = 0.5 * (V_f[1:] + V_f[:-1]) * dt", "ds = 0.5 * (V[1:] + V[:-1]) * dt", FREE_SIM),
    M("free_sim_lean_euler", "core/physics/terrain_sim.py",
      "x3 + w6 * (a3 + 2.0 * (b3 + c3) + d3)", "x3 + step * a3", FREE_SIM),
    M("free_sim_speed_euler", "core/physics/terrain_sim.py",
      "x5 + w6 * (a5 + 2.0 * (b5 + c5) + d5)", "x5 + step * a5", FREE_SIM),
    # -- the preview's stride (Live Preview's drag step on a Ground mesh) -----------------------
    M("preview_coarse_across_crossings", "core/physics/terrain_sim.py",
      "if rel * rel_y <= 0.0 or rel_y * (rel_y + y[4] * coarse[0]) <= 0.0:", "if False:",
      PREVIEW),
    M("preview_across_cells", "core/physics/terrain_sim.py",
      "and x5 <= fastest and", "and", PREVIEW),
    M("preview_no_reach", "core/physics/terrain_sim.py",
      "rel * (rel + x4 * reach) > 0.0:", "True:", PREVIEW),
    M("preview_first_stage_by_this_step", "core/physics/terrain_sim.py",
      "a0, a1, a2, a3, a4, a5, alpha, V_f, cf = stage(t, x0, x1, x2, x3, x4, x5, anchor, last,",
      "a0, a1, a2, a3, a4, a5, alpha, V_f, cf = stage(t, x0, x1, x2, x3, x4, x5, anchor, 3 * dt,",
      PREVIEW),
    M("preview_tables_ignored", "core/controllers/ellipse.py",
      "        if a == b:\n            return False", "        if True:\n            return False",
      PREVIEW),
    M("preview_tables_fine_without_a_new_lean", "core/controllers/ellipse.py",
      "        return (min(tm, top(feasible_turns(",
      "        return True or (min(tm, top(feasible_turns(", PREVIEW),
    M("preview_midpoint_slopes_held", "core/physics/terrain_sim.py",
      "dv = (hx + hxx * ex + hxy * ey, hy + hxy * ex + hyy * ey, hxx, hxy, hyy)",
      "dv = (hx, hy, hxx, hxy, hyy)", PREVIEW),
    M("preview_midpoints_read_twice", "core/physics/terrain_sim.py",
      "        if dv is not None:\n            hx, hy, hxx, hxy, hyy = dv",
      "        if dv is not None:\n            dv = derivatives(qx, qy)\n        if False:\n"
      "            hx, hy, hxx, hxy, hyy = dv", PREVIEW),
    M("preview_rows_at_fine_steps", "core/physics/terrain_sim.py",
      "row = stride == 1 or i % stride == 0", "row = True", PREVIEW),
    M("resample_window_from_the_next_sample", "core/physics/trajectory.py",
      "lo, hi = int(i[0]), int(i[-1]) + 2", "lo, hi = int(i[0]) + 1, int(i[-1]) + 2", TRAJ),
    M("resample_first_ignored", "core/physics/trajectory.py",
      "tn = t0 + np.arange(min(first, max(n, 0)), max(n, 0)) / fps",
      "tn = t0 + np.arange(max(n, 0)) / fps", TRAJ),
    M("free_sim_fall_from_normal", "core/physics/terrain_sim.py",
      "if abs(rel) > fall:", "if abs(x3) > fall:", FREE_SIM),
    M("terrain_law_lean_from_normal", "core/physics/model.py",
      "rel = st[3] - equilibrium_lean(controller, fr, t)", "rel = st[3]",
      [T + "test_terrain_fast.py", T + "test_terrain_smooth.py"]),
    M("straight_run_turns", "core/physics/terrain_one_figure.py",
      "cf = 0.0 * th  ", "cf = 0.0 * th + 0.01  ", FREE_SIM),
    M("proof_backs_up_the_largest", "core/planner/proof.py",
      "total[parent[ids], choice[ids]] = total[ids].min(axis=1)",
      "total[parent[ids], choice[ids]] = total[ids].max(axis=1)",
      [T + "test_planner_search.py"]),
    M("demo_slope_sine_grade", "core/ground/terrain_gen.py",
      "h = math.tan(math.radians(slope_deg)) * Y", "h = math.sin(math.radians(slope_deg)) * Y",
      TERMS),
    M("schedule_samples_held", "core/controllers/schedule.py",
      "return cls(lambda tt: float(np.interp(tt, t, v)))",
      "return cls(lambda tt: float(v[max(np.searchsorted(t, tt, side='right') - 1, 0)]))",
      TERMS + [T + "test_speed_schedule.py"]),
    M("follow_cap_without_path_curvature", "core/course/follow_problem.py",
      "curvature=0.0 if race else path_curvature_max(self.path),", "",
      [T + "test_follow_problem.py", T + "test_planner_speed_cap.py"]),
    M("follow_start_heading_reversed", "core/course/follow_problem.py",
      "heading = math.atan2(d[1], d[0])", "heading = math.atan2(-d[1], -d[0])",
      [T + "test_follow_problem.py"]),
    # -- the posed body from Winter's segment data (mapping/anthropometry.py), two-bone IK ------
    M("segment_no_parallel_axis", "mapping/anthropometry.py",
      "inertia += mi * (dot(d, d) - stack_dot(d, e) ** 2) + own", "inertia += own",
      ANTHRO, "mapping"),
    M("segment_rod_axis_ignored", "mapping/anthropometry.py",
      "own = (rg * length) ** 2 * (1.0 - stack_dot(u, e) ** 2)", "own = (rg * length) ** 2",
      ANTHRO, "mapping"),
    M("segment_com_from_distal", "mapping/anthropometry.py",
      "parts.append((frac * mass, a + at * seg,", "parts.append((frac * mass, b - at * seg,",
      ANTHRO, "mapping"),
    # -- the telemark turn (mapping/sports/telemark.py, Section 7: the skis at an angle) -------------
    M("telemark_skis_parallel", "mapping/sports/telemark.py",
      "yaw = traj.C_f * dy", "yaw = 0.0 * dy", TELEMARK, "mapping"),
    M("telemark_inside_ski_leads", "mapping/sports/telemark.py",
      'for s, sign in (("L", -1.0), ("R", 1.0)):', 'for s, sign in (("L", 1.0), ("R", -1.0)):',
      TELEMARK, "mapping"),
    M("fk_turns_of_the_wrong_bones", "mapping/kinematics.py",
      "np.stack([channels[b].rotation for b in turned])",
      "np.stack([channels[b].rotation for b in turned][::-1])",
      [T + "test_kinematics.py", T + "test_retarget.py"], "mapping"),
    M("two_bone_ik_lengths_swapped", "mapping/kinematics.py",
      "a = (l1 * l1 - l2 * l2 + dist * dist) / (2.0 * dist)",
      "a = (l2 * l2 - l1 * l1 + dist * dist) / (2.0 * dist)", [T + "test_kinematics.py"],
      "mapping"),
]

KERNELS = [T + "test_crowd_kernels.py"]
BATCH_REPORT = KERNELS + [T + "test_lean_report.py"]
KEYS = [T + "test_mapping_keys.py", T + "test_blender_fewer_keys.py"]
FEWER_KEYS = [T + "test_blender_fewer_keys.py"]
# -- the crowd's kernels and Fewer Keys (crowd/kernels.py, mapping/keys.py, blender/anim/fewer_keys.py)
MUTANTS += [
    M("crowd_kernel_always_floats", "crowd/kernels.py",
      'return "batch" if count >= BATCH_FROM else "floats"', 'return "floats"', KERNELS),
    M("crowd_batch_falls_after_its_span", "crowd/kernels.py",
      "if at is not None and at <= (n - 1) * dt + 1e-9:", "if at is not None:", KERNELS),
    M("batch_turns_not_kept", "core/controllers/ellipse.py",
      "            self._note_batch(t, w, tm, tmf)\n", "            pass\n",
      BATCH_REPORT),
    M("batch_worst_turn_the_least_limited", "core/controllers/ellipse.py",
      "worse = now[3] * rec[\"worst\"][2] < rec[\"worst\"][3] * now[2]",
      "worse = now[3] * rec[\"worst\"][2] > rec[\"worst\"][3] * now[2]",
      BATCH_REPORT),
    M("batch_last_turn_never_changes", "core/controllers/ellipse.py",
      "rec[\"last\"][:, changed] = now[:, changed]", "pass", BATCH_REPORT),
    M("batch_report_not_in_the_meta", "crowd/runner.py",
      "{**meta, **turn_meta(report)}", "meta", KERNELS),
    M("crowd_cli_lean_report_dropped", "cli/crowd.py",
      "    if turn is not None:              # the lean reached", "    if False:",
      [T + "test_crowd.py"]),
    M("keys_no_float32_margin", "mapping/keys.py",
      "    bound = bound - _float32_margin(values)\n", "", KEYS, "mapping"),
    M("keys_extrema_not_kept", "mapping/keys.py",
      "    keep[_extrema(values, bound)] = True\n", "", KEYS, "mapping"),
    M("keys_pruning_loose", "mapping/keys.py",
      "ok = worst[seg] <= bound", "ok = worst[seg] <= 2 * bound", KEYS, "mapping"),
    M("keys_quaternion_bound_loose", "mapping/keys.py",
      "return tol.angle / 4.0", "return tol.angle / 2.0", KEYS, "mapping"),
    M("keys_corner_slopes_swapped", "mapping/keys.py",
      "(u3 - 2 * u2 + u) * h * kd[j, 1]", "(u3 - 2 * u2 + u) * h * kd[j, 0]", KEYS, "mapping"),
    M("keys_no_corners", "mapping/keys.py",
      "return slopes(frames, values, bound / step)", "return slopes(frames, values)", KEYS,
      "mapping"),
    M("fewer_keys_aligned_at_corners", "blender/anim/fewer_keys.py",
      "kind = np.where(d[:, 0] == d[:, 1], aligned, free).astype(np.int32)",
      "kind = np.full(n, aligned, np.int32)", FEWER_KEYS, "bake"),
    M("fewer_keys_fingerprint_stale", "blender/anim/fewer_keys.py",
      "    bake_layers.fingerprint(action, bag)      # the bake's own keys", "    pass  #",
      FEWER_KEYS, "bake"),
]
# -- grip and skidding (core/physics/grip.py, core/physics/skidding.py, core/planner/speed_cap.py) -
SKID = [T + "test_skidding.py", T + "test_grip_cyclist.py", T + "test_cli_skidding.py",
        T + "test_planner_speed_cap.py"]
SKID_MUTANTS = [
    M("grip_circle_added", "core/physics/grip.py",
      "b = xp.maximum((mu_grip * N_m) ** 2 - F_lat * F_lat, 0.0) ** 0.5",
      "b = xp.maximum((mu_grip * N_m) ** 2 + F_lat * F_lat, 0.0) ** 0.5", SKID),
    M("grip_skid_uncapped_in_turns", "core/physics/grip.py",
      "if skid_max < SKID_MAX_STOP:", "if False:", SKID),
    M("grip_edge_ignored", "core/physics/grip.py",
      "return min(math.tan(min(abs(edge) + self.shear_angle, 0.49 * math.pi)), self.mu)",
      "return min(math.tan(min(self.shear_angle, 0.49 * math.pi)), self.mu)", SKID),
    M("grip_lateral_no_lean_acceleration", "core/physics/grip.py",
      "return V * V_f * C_f + l * (alpha_v * c - omega_v * omega_v * s) - frame.g_lateral",
      "return V * V_f * C_f - frame.g_lateral", SKID),
    M("grip_skid_angle_unsigned", "core/physics/grip.py",
      "return s * xp.atan2(brake, xp.abs(F_lat))", "return xp.atan2(brake, xp.abs(F_lat))",
      SKID),
    M("model_brake_at_body_speed", "core/physics/model.py",
      "dV = dV - brake.bound(N / body.m, F_lat, th) * ratio",
      "dV = dV - brake.bound(N / body.m, F_lat, th)", SKID),
    M("fused_brake_dropped", "core/physics/terrain_one_figure.py",
      "dV -= b * ratio", "dV -= 0.0 * b * ratio", SKID),
    M("fused_lateral_no_lean_acceleration", "core/physics/terrain_one_figure.py",
      "F_lat = V * V_f * cf + l * (alpha * cs - om * om * sn) - g_b",
      "F_lat = V * V_f * cf - g_b", SKID),
    M("skid_integral_never", "core/physics/skidding.py",
      "self.integral = max(0.0, self.integral + e * dt / (r.tau * r.reset_time))",
      "self.integral = 0.0", SKID),
    M("skid_stop_edge_flat", "core/physics/skidding.py",
      "0.0 if r.grip.kind == \"tyre\" else STOP_EDGE)", "0.0)", SKID),
    M("skid_tyre_lean_uncapped", "core/physics/skidding.py",
      "Schedule.constant(min(const, cap))", "Schedule.constant(const)", SKID),
    M("skid_no_standing", "core/physics/terrain_sim.py",
      "rows, stop = stand_rows(rows, n, ground, body.g, skidding.grip), None",
      "stop = None", SKID),
    M("speed_cap_brakes_below", "core/planner/speed_cap.py",
      "want = np.where(over > 0.0, np.maximum(d[5] + over / self.tau, 0.0), 0.0) / ratio",
      "want = np.maximum(d[5] + over / self.tau, 0.0) / ratio", SKID),
    M("wedge_no_hold", "core/physics/skidding.py",
      "b = max(0.0, hold + e / r.tau + self.integral)",
      "b = max(0.0, e / r.tau + self.integral)", SKID),
    M("wedge_bound_at_g", "core/physics/skidding.py",
      "(N_m if N_m > 0.0 else self.g)", "self.g", SKID),
    M("round_turns_no_slope_pull", "core/controllers/braking.py",
      "/ math.cos(th) - pull * math.sin(p)) / V", "/ math.cos(th)) / V", SKID),
    M("round_turns_no_lean_acceleration", "core/controllers/braking.py",
      "return ((g_n * math.sin(th) + wj * th) / math.cos(th)",
      "return ((g_n * math.sin(th)) / math.cos(th)", SKID),
    M("round_turns_mean_line_free", "core/controllers/braking.py",
      "want = -math.atan(lateral / (V * self.period(t)))", "want = 0.0", SKID),
    M("gs_racer_sport_drag", "core/equipment.py",
      "return res if self.drag_area is None else replace(res, CdA=self.drag_area)",
      "return res", SKID),
    M("speed_cap_no_lean_bound", "core/planner/speed_cap.py",
      "lateral = min(self.grip.mu, math.tan(min(self.lean_bound, 1.5)))",
      "lateral = self.grip.mu", SKID),
]
MUTANTS += SKID_MUTANTS + [
    M("bake_skidding_dropped", "blender/jobs/pipeline.py",
      "target_speed=target, skidding=skidding, stride=stride)",
      "target_speed=target, stride=stride)",
      [T + "test_blender_skidding.py"], group="bake"),
    M("follow_path_ignores_target", "blender/scene/follow_ground.py",
      "    if target > 0.0:                      # the planner brakes", "    if False:",
      [T + "test_blender_skidding.py"], group="bake"),
]
# The skid on the rig, the beginner's and the recreational skier's habits, the brushed tracks
# (docs/skidding.md Section 8).
SKID_POSE = [T + "test_mapping_skid.py"]
MUTANTS += [
    M("skid_pose_skis_not_turned", "mapping/sports/skid_pose.py",
      "return {s: (dy, yaw + self.yaw(s), heel)", "return {s: (dy, yaw, heel)", SKID_POSE,
      group="mapping"),
    M("skid_pose_wedge_tips_apart", "mapping/sports/skid_pose.py",
      'half = np.abs(self.skid) * (1.0 if s == "R" else -1.0)',
      'half = np.abs(self.skid) * (1.0 if s == "L" else -1.0)', SKID_POSE, group="mapping"),
    M("skid_pose_stop_downhill_edge", "mapping/sports/skid_pose.py",
      "side = 1.0 if np.sum(self.skid[self.stopping]) >= 0.0 else -1.0",
      "side = -1.0 if np.sum(self.skid[self.stopping]) >= 0.0 else 1.0", SKID_POSE,
      group="mapping"),
    M("skid_pose_no_lean_back", "mapping/sports/skid_pose.py",
      "add_local_rotation(b, B.LEAN, (1.0, 0.0, 0.0), self.pitch)",
      "add_local_rotation(b, B.LEAN, (1.0, 0.0, 0.0), 0.0 * self.pitch)", SKID_POSE,
      group="mapping"),
    M("skid_pose_lean_back_without_mass", "mapping/sports/skid_pose.py",
      "want = np.arctan2(m * brake,", "want = np.arctan2(brake,", SKID_POSE, group="mapping"),
    M("skid_pose_no_counter_rotation", "mapping/sports/skid_pose.py",
      "(CHEST_SHARE - HIP_SHARE) / 3.0 * self.body_skid()", "0.0 * self.body_skid()",
      SKID_POSE, group="mapping"),
    M("skid_pose_board_not_turned", "mapping/sports/snowboarder.py",
      "R = rot_z(skid.yaw()) @ R", "R = R", SKID_POSE, group="mapping"),
    M("skid_pose_goofy_skid_unmirrored", "mapping/retarget/stance.py",
      '"C_f", "skid"):', '"C_f"):', SKID_POSE, group="mapping"),
    M("brushed_band_groove_only", "mapping/sports/skid_pose.py",
      "0.5 * length * np.abs(np.sin(np.asarray(skid, float)))", "0.0 * length", SKID_POSE,
      group="mapping"),
    M("habit_style_ignored", "cli/terrain_flags.py",
      "style = habit.style if habit is not None else", 'style = "skid" if False else',
      [T + "test_skier_presets.py"]),
    M("track_ignores_skid", "blender/render/terrain.py",
      "half = brushed_half_width(half, equipment_length(load_rig(record.name)), skid)",
      "half = half + 0.0 * skid", [T + "test_blender_skidding.py"], group="bake"),
]

IGNORE = shutil.ignore_patterns(".git", ".venv*", "__pycache__", ".hypothesis", ".pytest_cache",
                                "out", "dist", "*.egg-info", "build")


def stale(mutants) -> list:
    """``(mutant, reason)`` for each mutant whose snippet is not exactly once in its file."""
    out = []
    for m in mutants:
        path = ROOT / PKG / m.file
        if not path.exists():
            out.append((m, f"{PKG}/{m.file} does not exist"))
            continue
        n = path.read_text().count(m.find)
        if n != 1:
            out.append((m, f"snippet found {n} times in {PKG}/{m.file} (need exactly 1): "
                           f"{m.find!r}"))
    return out


def pytest_cmd(python, tests):
    return [python, "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider", "-o", "addopts=",
            "--no-header", *tests]


def run_tests(python, tree, tests, timeout):
    """``(status, seconds, tail)``: status 'pass', 'fail' or 'timeout'."""
    env = dict(os.environ, PYTHONPATH=str(tree), PYTHONDONTWRITEBYTECODE="1",
               BLENDER_USER_RESOURCES=str(tree / ".blender-user"))
    t0 = time.perf_counter()
    try:
        r = subprocess.run(pytest_cmd(python, tests), cwd=tree, env=env, capture_output=True,
                           text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return "timeout", time.perf_counter() - t0, ""
    tail = (r.stdout.strip().splitlines() or [""])[-1]
    return ("pass" if r.returncode == 0 else "fail"), time.perf_counter() - t0, tail


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", nargs="+", metavar="NAME", help="run only these mutants")
    ap.add_argument("--group", choices=("core", "mapping", "registry", "bake", "live", "share"),
                    action="append",
                    help="run only these groups (repeatable; default all)")
    ap.add_argument("--list", action="store_true", help="list the mutants and exit")
    ap.add_argument("--python", default=sys.executable, help="interpreter for pytest")
    ap.add_argument("--timeout", type=float, default=300.0, help="seconds per mutant")
    ap.add_argument("--skip-stale", action="store_true",
                    help="run the mutants still found; list the stale ones")
    ap.add_argument("--goal", type=float, default=0.9)
    ap.add_argument("--json", metavar="FILE", help="write the results as JSON")
    ap.add_argument("--exclude-tests", metavar="SUBSTRING",
                    help="leave out the test files whose name contains this (for example "
                         "mutation_guards: the score without the guards)")
    args = ap.parse_args(argv)
    args.python = str(Path(args.python).absolute())    # pytest runs in the copy (not resolved:
    #                                                    a venv's python is a symlink)

    mutants = [m for m in MUTANTS if (not args.only or m.name in args.only)
               and (not args.group or m.group in args.group)]
    if args.only:
        unknown = set(args.only) - {m.name for m in MUTANTS}
        if unknown:
            print(f"mutate: no mutant named {', '.join(sorted(unknown))}", file=sys.stderr)
            return 2
    if args.list:
        for m in mutants:
            print(f"{m.name:32s} {m.group:8s} {PKG}/{m.file}")
        print(f"{len(mutants)} mutants")
        return 0
    bad = stale(mutants)
    for m, why in bad:
        print(f"mutate: STALE mutant {m.name}: {why}", file=sys.stderr)
    if bad and not args.skip_stale:
        print("mutate: update the snippets above (the code changed), or run with --skip-stale",
              file=sys.stderr)
        return 2
    mutants = [m for m in mutants if m not in {b for b, _ in bad}]
    if args.exclude_tests:
        mutants = [replace(m, tests=tuple(t for t in m.tests if args.exclude_tests not in t))
                   for m in mutants]

    with tempfile.TemporaryDirectory(prefix="turning-mutate-") as tmp:
        tree = Path(tmp) / "tree"
        shutil.copytree(ROOT, tree, ignore=IGNORE)
        # Baseline: every test set must pass on the unmutated copy.
        for tests in sorted({m.tests for m in mutants}):
            status, sec, tail = run_tests(args.python, tree, tests, args.timeout * 2)
            print(f"baseline {status:7s} {sec:6.1f} s  {' '.join(Path(t).name for t in tests)}")
            if status != "pass":
                print(f"mutate: the unmutated tree fails these tests ({tail}); fix that first",
                      file=sys.stderr)
                return 2
        results = []
        for k, m in enumerate(mutants, 1):
            path = tree / PKG / m.file
            original = path.read_text()
            path.write_text(original.replace(m.find, m.replace, 1))
            try:
                status, sec, tail = run_tests(args.python, tree, m.tests, args.timeout)
            finally:
                path.write_text(original)
            caught = status != "pass"
            results.append({"name": m.name, "file": f"{PKG}/{m.file}", "group": m.group,
                            "status": "caught" if caught else "SURVIVED",
                            "how": status if caught else "", "seconds": round(sec, 1),
                            "tail": tail})
            print(f"[{k:2d}/{len(mutants)}] {'caught' if caught else 'SURVIVED':8s} "
                  f"{status:7s} {sec:6.1f} s  {m.name}  ({PKG}/{m.file})", flush=True)

    caught = sum(r["status"] == "caught" for r in results)
    score = caught / len(results) if results else 0.0
    print(f"\nscore: {caught}/{len(results)} caught = {100 * score:.1f}%  "
          f"(goal {100 * args.goal:.0f}%)")
    survivors = [r["name"] for r in results if r["status"] != "caught"]
    if survivors:
        print("survivors: " + ", ".join(survivors))
    if bad:
        print("stale (not run): " + ", ".join(m.name for m, _ in bad))
    if args.json:
        Path(args.json).write_text(json.dumps({"score": score, "caught": caught,
                                               "total": len(results), "results": results,
                                               "stale": [m.name for m, _ in bad]}, indent=1))
    return 0 if score >= args.goal else 1


if __name__ == "__main__":
    sys.exit(main())
