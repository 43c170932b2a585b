"""A starter axis description: ``servotune init DIR`` writes it.

The template is a complete, loadable axis: a small lumped model of a ball-screw feed axis
(motor rotor and stator, two guide-way pads, the linear-encoder head and the work piece) in
``structure.npz``, and an ``axis.toml`` whose every field carries a comment with its unit and
meaning. Replace the structure by your FE matrices (see the ``[structure]`` comments) and the
numbers by your axis' data.
"""

from __future__ import annotations

import io
import math
import re
from pathlib import Path

import numpy as np

from .report import check_writable, write_atomically

__all__ = ["template_structure", "write_template", "template_toml", "axis_name_for",
           "TEMPLATE_TOML"]

RATIO = 10e-3 / (2 * math.pi)  # 10 mm lead, direct drive [m/rad]


def template_structure() -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Return mass, stiffness and DOF names of the template's lumped feed axis (SI).

    Motor rotor 0.012 kg m^2 on a torsional bracket (stator 0.03 kg m^2, 2e5 N m/rad);
    ball screw, nut and bearings 3e8 N/m between r * rotor angle and the slide (r = 10 mm
    lead / 2 pi); slide 800 kg in two halves at the pads (2e9 N/m between them); encoder head
    2 kg on 5e8 N/m; table, fixture and work piece 300 kg on 1.5e8 N/m.

    Returns
    -------
    mass : numpy.ndarray
        Mass matrix [kg, kg m^2].
    stiffness : numpy.ndarray
        Stiffness matrix [N/m, N m/rad].
    dofs : list of str
        The DOF names.
    """
    dofs = ["motor.rotor", "motor.stator", "pad1.x", "pad2.x", "encoder.x", "wp.x"]
    idx = {d: i for i, d in enumerate(dofs)}
    m = np.diag([0.012, 0.03, 400.0, 400.0, 2.0, 300.0])
    k = np.zeros((6, 6))

    def spring(a, b, value, ca=1.0):
        vec = np.zeros(6)
        vec[idx[a]] += ca
        if b is not None:
            vec[idx[b]] -= 1.0
        k[:] += value * np.outer(vec, vec)

    spring("motor.rotor", "pad1.x", 3.0e8, ca=RATIO)
    spring("motor.stator", None, 2.0e5)
    spring("pad1.x", "pad2.x", 2.0e9)
    spring("pad2.x", "encoder.x", 5.0e8)
    spring("pad2.x", "wp.x", 1.5e8)
    return m, k, dofs


_TEMPLATE = f'''\
# Axis description for servotune. Values are SI (m, N, s, kg, rad) unless the key says
# otherwise (_hz, _deg, _db, _rpm, kv_m_per_min_per_mm). Check it with
#   servotune modes THIS_FOLDER        and tune it with   servotune tune THIS_FOLDER

[axis]
name = "{{AXIS_NAME}}"{{NAME_PAD}} # a short name (used for output folders)
description = "Starter axis written by servotune init: a lumped ball-screw axis"

[structure]
file = "structure.npz"              # npz with arrays mass, stiffness (n x n) and dofs (n names)
modal_damping = 0.03                # damping ratio of every mode (or a list, one per mode)
# FE matrices instead of a reduced model (MatrixMarket .mtx/.mmf, Harwell-Boeing
# .hb/.rsa/.rua/.hbmat, MATLAB .mat, .npz), reduced by Craig-Bampton on loading to the boundary
# DOFs plus n_modes fixed-interface modes:
#   mass = "M.mtx"
#   stiffness = "K.mtx"
#   dof_map = "dofs.csv"            # one DOF name per matrix row (header "name")
#   [structure.reduce]              # (a sub-table: an inline table cannot span lines)
#   boundary = ["pad1.x", "pad2.x", "wp.x", "wp.y", "wp.z", "motor.rotor", "motor.stator",
#               "encoder.x"]
#   n_modes = 30                    # or f_max_hz = 500.0
# DOF names: pad<i>.x = relative X at a guide-way pad (slide minus guide way), wp.x/y/z = the
# work-piece point, motor.rotor/motor.stator = rotations, encoder.x = linear-encoder head.

[friction]                          # all axis friction, lumped at the guide-way pads
pads = ["pad1.x", "pad2.x"]         # relative-X DOFs of the pads; friction is shared equally
viscous = 5578.0                    # viscous-only model and initial guide-way damping [N s/m]
# measurements = {{ stribeck = "stribeck.csv" }}   # identify (Fc, Fs, vs, delta, sigma2) from a
#                                     CSV with columns v_m_per_s, f_n (both velocity signs)

[friction.lugre]                    # axis totals (or lugre = "bianchi2014", a named set)
fc = 2198.0                         # Coulomb friction [N]
fs = 6013.0                         # static friction [N]
vs = 0.01                           # Stribeck velocity [m/s]
delta = 1.0                         # Stribeck exponent [-]
sigma0 = 5.9e9                      # bristle stiffness [N/m]
sigma1 = 1.6e7                      # bristle damping [N s/m]
sigma2 = 5578.0                     # viscous friction [N s/m]
sigma1_decay_speed = 1.0e-3         # the bristle damping fades above this speed [m/s] (Olsson
                                    # et al. 1998): below 4 sqrt(2e) fc/sigma1 the contact is
                                    # passive; with a constant sigma1 the sliding pads can
                                    # stick-slip (see models/paper_x_axis/README.md)

[drive]
encoder = "linear"                  # position feedback: "linear" (DOF encoder.x) or "motor"

[drive.motor]
rotor = "motor.rotor"               # rotation DOFs; the torque acts between rotor and stator
stator = "motor.stator"
torque_constant = 1.2               # kt [N m/A]
back_emf_constant = 1.2             # ke [V s/rad]
resistance = 0.4                    # R [ohm]
inductance = 3.0e-3                 # L [H]
torque_peak = 36.0                  # largest torque (converter current limit x kt) [N m]
torque_continuous = 12.0            # rated, thermally continuous torque [N m]
speed_max_rpm = 3000.0              # largest motor speed [rpm] (sets the rapid speed)
# the torques over speed (default: torque_peak and torque_continuous at every speed up to
# speed_max_rpm): the data sheet's curve, linear between its points, from 0 rpm to the top speed
# torque_speed = {{ speed_rpm = [0, 2000, 3000], peak = [36, 36, 24], continuous = [12, 12, 8] }}
# rated_speed_rpm = 2000.0          # or: the torques fall at constant power above this [rpm]

[drive.sampling]                    # the digital drive (delays cost phase: margins include them)
current_period = 125.0e-6           # sample period of the current controller [s]
velocity_period = 125.0e-6          # of the speed controller [s] (speed from encoder positions)
position_period = 1.0e-3            # of the position controller [s]
computation_delay = 1.0             # sampling to output, in sample periods
speed_filter = 0.0                  # time constant of a speed-measurement filter [s]
# continuous = true                 # instead: the paper's continuous drive (no delays)

[drive.transmission]
ratio = {RATIO!r}         # slide travel per motor radian [m/rad] = lead / (2 pi) / belt ratio

[drive.current_loop]                # PI on the winding current
kp = 15.0                           # [V/A]
ti = 2.0e-3                         # [s]

[drive.velocity_loop]               # PI on the motor speed
kp = 3.7                            # [N m s/rad]
ti = 12.0e-3                        # [s]

[drive.position_loop]               # P on the position error
kv_m_per_min_per_mm = 1.0           # the machine-tool Kv factor, or kv = 16.67 [1/s]

# [drive.feedforward]
# velocity = 1.0                    # velocity feed-forward gain [-]
# torque_inertia = 0.015            # inertia for the torque feed-forward [kg m^2]
# [drive.filters]
# lowpass_hz = 800.0                # 2nd-order low-pass on the torque set-point [Hz]
# notch_hz = 410.0                  # notch on the torque set-point [Hz]; a list for several
# notch_width = 0.5                 # relative -3 dB width [-] (one per notch_hz)
# notch_depth = 0.1                 # gain at the notch frequency [-] (one per notch_hz)

[cutting]                           # the milling operation for the chatter limit
teeth = 4
kt = 2.0e9                          # tangential cutting coefficient [N/m^2]
kn = 0.6e9                          # normal (radial) cutting coefficient [N/m^2]
radial_immersion = 0.5              # a/D in [0.001, 1]
milling = "down"                    # "down" or "up"
speed_rpm = [3000.0, 12000.0]       # spindle-speed range [rpm]
direction = "x"                     # the flexible (feed) direction: "x" or "y"
feed_per_tooth = 1.0e-4             # [m]; with teeth and speed_rpm it gives the feed speeds

[operation]                         # the regimes the axis works in (all keys optional)
# feed_speeds = [0.01, 0.05]        # slide speeds while cutting [m/s] (default from [cutting])
# rapid_speed = 0.5                 # [m/s] (default from speed_max_rpm and the transmission)
acceleration = 2.0                  # of rapid moves [m/s^2]
# process_force_pp = 300.0          # cutting force p-p at the work piece [N] (default from
#                                     [cutting] at the required depth)
# standing = true                   # the axis also cuts standing still

[requirements]
ms_velocity_max = 2.0               # largest sensitivity peak of the velocity loop
ms_position_max = 1.5               # largest sensitivity peak of the position loop
phase_margin_min_deg = 40.0         # each margin tightens the Ms limits (Ms disk)
gain_margin_min_db = 6.0
# kv_min_m_per_min_per_mm = 1.0     # smallest Kv the tuning may choose
band_hz = [5.0, 300.0]              # band of the compliance-peak objective [Hz]
depth_required = 2.0e-3             # required axial depth of cut [m]
# thrust_margin = 0.2               # fraction of the motor's thrust kept in reserve
# bandwidth_ratio_min = 4.0         # velocity-loop bandwidth >= this x position-loop bandwidth
# current_bandwidth_ratio_min = 3.0 # current-loop bandwidth >= this x velocity-loop bandwidth
# ti_bandwidth_min = 3.0            # Ti x velocity-loop bandwidth within [min, max]
# ti_bandwidth_max = 30.0
# nonlinear_tolerance = 0.3         # the nonlinear axis may peak this much above the claim

[tuning]                            # what `servotune tune` may change, and within which bounds
free = ["c", "kv", "kp", "ti", "notch"]  # guide-way damping C, Kv, velocity-loop Kp and Ti,
                                    # and a current set-point notch (frequency, width, depth);
                                    # add "lowpass" to tune the corner of lowpass_hz
# c = [5578.0, 1.0e8]               # [N s/m] axis total (default: from the guide ways' own
#                                     viscous friction sigma2 up: damping is added, not removed)
kv = [1.0, 300.0]                   # [1/s]
# kp = [0.04, 370.0]                # [N m s/rad] (default: a factor 100 around the initial kp)
ti = [1.0e-3, 0.2]                  # [s]; <= 0.2 s keeps integral action in the velocity loop
# lowpass_hz = [200.0, 3000.0]     # [Hz] the tuned low-pass' corner, with "lowpass" in free
#                                     (default: 1/8 to 4 x lowpass_hz, below 0.45 x the current
#                                     controller's sample rate)
chatter_weight = 0.0                # 0: compliance peak only; 1: chatter limit only
# friction_spread = {{ fc = 0.3, sigma0 = 3.0 }}   # tune for the friction spread too (fractions
#                                     for fc, fs, sigma1; a factor for sigma0)
'''


def axis_name_for(folder) -> str:
    """Return the axis name ``init`` gives a folder: its name, in letters, digits and ``_ . -``.

    Parameters
    ----------
    folder : str or os.PathLike
        The axis folder.

    Returns
    -------
    str
        The folder's name (of its resolved path) with every run of other characters replaced
        by ``_`` and ``. _ -`` stripped from the ends; ``"my_axis"`` when nothing is left.

    Examples
    --------
    >>> axis_name_for("projects/X axis (rev 2)")
    'X_axis_rev_2'
    >>> axis_name_for(".")  != ""
    True
    """
    name = Path(folder).resolve().name
    name = re.sub(r"[^A-Za-z0-9_.-]+", "_", name)
    name = re.sub(r"_{2,}", "_", name).strip("._-")
    return name or "my_axis"


#: The template's last ``[requirements]`` line: the settings of requirement plug-ins follow it.
_REQUIREMENTS_END = "# nonlinear_tolerance = 0.3 "


def setting_lines(declared) -> str:
    """Return commented ``[requirements]`` lines for settings that requirements declare.

    Parameters
    ----------
    declared : Mapping of str to (Setting, str)
        Name -> (declaration, the declaring requirement), as
        :func:`servotune.tuning.constraint.declared_settings` returns them.

    Returns
    -------
    str
        One commented line per setting: the default (or the low end of the range when it has
        none), the unit, the help, the range and the requirement; empty without settings.

    Examples
    --------
    >>> from servotune.requirements import Setting
    >>> line = setting_lines({"e_max_m": (Setting("e_max_m", "m", None, 1e-7, 1e-2,
    ...                                           "largest error"), "following_error")})
    >>> line.split("#")[1].strip()
    'e_max_m = 1e-07'
    >>> line.split("#")[2].strip()
    "[m] largest error, in [1e-07, 0.01] (requirement 'following_error'; off when absent)"
    """
    lines = []
    for key, (setting, owner) in sorted(declared.items()):
        value = setting.low if setting.default is None else setting.default
        default = ("off when absent" if setting.default is None
                   else f"default {setting.default:g}")
        lines.append(f"# {key} = {value:g}".ljust(36) + f"# [{setting.unit}] {setting.help}, "
                     f"in [{setting.low:g}, {setting.high:g}] (requirement {owner!r}; "
                     f"{default})")
    return "\n".join(lines)


def template_toml(name: str = "my_axis", settings=None) -> str:
    """Return the commented ``axis.toml`` of the starter axis, with ``[axis] name`` = ``name``.

    Parameters
    ----------
    name : str, optional
        The axis name (default "my_axis").
    settings : Mapping of str to (Setting, str), optional
        Settings of requirement plug-ins to list (commented) under ``[requirements]``
        (:func:`setting_lines`).

    Returns
    -------
    str
        The TOML text.
    """
    if not re.fullmatch(r"[A-Za-z0-9_.-]+", name):
        raise ValueError(f"axis name {name!r}: use letters, digits and _ . - only")
    text = _TEMPLATE.replace("{AXIS_NAME}", name).replace(
        "{NAME_PAD}", " " * max(0, 26 - len(name)))
    extra = setting_lines(settings or {})
    if extra:
        at = text.index("\n", text.index(_REQUIREMENTS_END))
        text = text[:at] + "\n" + extra + text[at:]
    return text


TEMPLATE_TOML = template_toml("my_axis")  # the text with the default name


def write_template(folder, force: bool = False, name: str = "my_axis") -> list[Path]:
    """Write the starter axis (``axis.toml`` and ``structure.npz``) into ``folder``.

    Parameters
    ----------
    folder : path-like
        Created if needed.
    force : bool
        Replace existing files.
    name : str
        ``[axis] name``; ``servotune init`` passes the folder's name (:func:`axis_name_for`).

    Returns
    -------
    list of pathlib.Path
        The files written, ``axis.toml`` then ``structure.npz``.

    Raises
    ------
    OutputExistsError
        If a file exists and ``force`` is False (nothing is written then).
    """
    folder = Path(folder)
    files = [folder / "axis.toml", folder / "structure.npz"]
    check_writable(files, force)
    from .tuning.constraint import declared_settings

    text = template_toml(name, declared_settings())
    m, k, dofs = template_structure()
    buffer = io.BytesIO()
    np.savez(buffer, mass=m, stiffness=k, dofs=np.array(dofs))
    write_atomically(files[1], buffer.getvalue(), force)
    write_atomically(files[0], text, force)
    return files
