"""The papers' robots as parametric URDFs.

One function per robot of Shoham & Koren (1987) and Barker (1983). Each takes the paper's
lengths as keyword arguments (metres; angles in radians), named as in the papers in lower
case, and returns a :class:`pinrate.Robot` with the paper's tip and sensor frames;
:func:`urdf` returns the URDF text. The files in the project's ``urdf/`` folder are these
functions' output with the default (paper) values.

Conventions (each derived so that pinrate's sensor-frame Jacobian reproduces the paper's
printed matrix; the tests check every one against its closed form):

* ``two_link_planar`` (Fig. 1, eq. 10): joints theta1, theta2 about z; sensor = tip at the
  arm end, x along link 2. J_linear(x, y) = [[l1 S2, 0], [l2 + l1 C2, l2]].
* ``cylindrical`` (eq. 13): theta1 about the vertical, d2 up, d3 radial; sensor at the arm
  end with x tangential, y up, z radial: J_linear = diag(d3, 1, 1).
* ``spherical`` (Fig. 2, eq. 16): theta1 about the vertical, theta2 elevation, d3 radial;
  sensor x tangential, y "pointing up in the direction of theta2", z radial:
  J_linear = diag(d3 C2, d3, 1).
* ``cartesian``: three prismatic joints along x, y, z and a wrist z-y-x whose axes meet at
  the TCP, the sensor there: J = identity-like and B = U = 0 (the ideal sensor robot, §3).
* ``planar_polar`` (Fig. 4, eq. 55): theta1, d2 (radial), theta3; link l = 0.2; sensor on
  the second link (x along d2) at the theta3 axis.
* ``scara`` (Fig. 7, eq. 59): theta1, theta2, d (vertical), theta3; l1 = l2 = l3 = 0.4;
  sensor on the second link (x along link 2) at the theta3 axis; l3 is the tool length.
* ``hirata_arh300``: the SCARA with l2 = 0.275 m, 25° <= theta2 <= 145° (§5.2) and a tool
  length l3 (default 0.05 m). l1 is not given by the paper: 0.325 m assumed (it does not
  enter G, eq. 60).
* ``spherical_6dof`` (Fig. 11, eq. 70): spherical arm theta1, theta2 (about the horizontal
  axis, positive pointing down), d3, and a wrist z-x-z (theta4, theta5, theta6) meeting at
  P; sensor at P on the third link (z radial, x along the theta2 axis); TCP at tool length l
  beyond P along the theta6 axis (a frame ``wrist_centre`` at P on the last link gives
  B = 0). -90° < theta5 < 90° as in §5.3. Eq. 70's printed second column is a misprint: see
  :mod:`pinrate.papers.spherical_6dof`.
* ``barker_arm`` (Barker appendix A): the DH table with NO, ES, SN, WE, HW and alpha3, a3,
  r3. URDF link i is DH frame i-1 turned by theta_i about z_{i-1}; the next joint's origin
  is Rz(offset_i) Tz(r_i) Tx(a_i) Rx(alpha_i), so theta'_i = theta_i + offset_i as in the
  table. The lengths are symbolic in the paper: the defaults are PUMA-560-like (NO 0.6604,
  ES 0.4318, SN 0.1491, WE 0.4331, HW 0.0563 m) with the nominal alpha3 = 90°, a3 = r3 = 0.
  Tip: the wrist centre (frames 4 and 5 coincide there; axes of the hand); sensor: the hand
  frame 6 (the operator's TVEL/RVEL frame).
"""

from __future__ import annotations

import inspect
import math
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..checks import PHYSICAL_BOUND, check_name, check_output_folder, check_positive
from ..errors import InputError, choices_hint
from ..kinematics.manipulator import Robot
from ..kinematics.urdf import robot_from_urdf
from .urdf_writer import Joint, Shape, UrdfBuilder, axis_rotation, rod

_PI = math.pi
_DEG = _PI / 180.0


@dataclass
class _Design:
    """A generated robot: its URDF, the paper's tip and sensor frames, a non-singular home."""

    urdf: UrdfBuilder
    tip: str
    sensor: str
    home: dict[str, float]


def _positive(name: str, value: float) -> float:
    return check_positive(value, f"length {name} (m)")


def _finite(name: str, value: float) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not abs(value) <= PHYSICAL_BOUND:
        raise InputError(f"parameter {name} must be a finite number within ±{PHYSICAL_BOUND:g}, got {value!r}")
    return float(value)


# ---------------------------------------------------------------------- the robots
def _two_link_planar(l1: float = 0.4, l2: float = 0.4) -> _Design:
    l1, l2 = _positive("l1", l1), _positive("l2", l2)
    u = UrdfBuilder("two_link_planar")
    u.link("base", Shape("cylinder", (0.05, 0.05), colour="dark"))
    u.joint(Joint("theta1", "revolute", "base", "link1"))
    u.link("link1", rod((0, 0, 0), (l1, 0, 0), colour="blue"))
    u.joint(Joint("theta2", "revolute", "link1", "link2", xyz=(l1, 0, 0)))
    u.link("link2", rod((0, 0, 0), (l2, 0, 0), colour="orange"))
    u.joint(Joint("tip_joint", "fixed", "link2", "tip", xyz=(l2, 0, 0)))
    return _Design(u, "tip", "tip", {"theta2": _PI / 2})


def _cylindrical(d2_max: float = 1.0, d3_max: float = 1.0) -> _Design:
    d2_max, d3_max = _positive("d2_max", d2_max), _positive("d3_max", d3_max)
    u = UrdfBuilder("cylindrical")
    u.link("base", rod((0, 0, 0), (0, 0, d2_max), 0.03, "dark"))
    u.joint(Joint("theta1", "revolute", "base", "column"))
    u.joint(Joint("d2", "prismatic", "column", "carriage", limits=(0.0, d2_max)))
    u.link("carriage", Shape("box", (0.08, 0.08, 0.08), colour="blue"))
    u.joint(Joint("d3", "prismatic", "carriage", "arm", axis=(1, 0, 0), limits=(0.1 * d3_max, d3_max)))
    u.link("arm", rod((-0.3 * d3_max, 0, 0), (0, 0, 0), 0.02, "orange"))
    # Sensor at the arm end: x tangential (+y of the arm), y up (+z), z radial (+x).
    sensor_rotation = np.column_stack([[0, 1, 0], [0, 0, 1], [1, 0, 0]]).astype(float)
    u.joint(Joint("sensor_joint", "fixed", "arm", "sensor", sensor_rotation))
    return _Design(u, "sensor", "sensor", {"d2": 0.5 * d2_max, "d3": 0.5 * d3_max})


def _spherical(d3_max: float = 1.0) -> _Design:
    d3_max = _positive("d3_max", d3_max)
    u = UrdfBuilder("spherical")
    u.link("base", Shape("cylinder", (0.06, 0.1), colour="dark"))
    u.joint(Joint("theta1", "revolute", "base", "turret"))
    # theta2 raises the arm: a rotation about -y of the turret lifts its x axis.
    u.joint(Joint("theta2", "revolute", "turret", "boom", axis=(0, -1, 0), limits=(-_PI / 2, _PI / 2)))
    u.link("boom", Shape("sphere", (0.05,), colour="blue"))
    u.joint(Joint("d3", "prismatic", "boom", "arm", axis=(1, 0, 0), limits=(0.1 * d3_max, d3_max)))
    u.link("arm", rod((-0.3 * d3_max, 0, 0), (0, 0, 0), 0.02, "orange"))
    # Fig. 2: x tangential (arm +y), y up in the direction of theta2 (arm +z), z radial (arm +x).
    sensor_rotation = np.column_stack([[0, 1, 0], [0, 0, 1], [1, 0, 0]]).astype(float)
    u.joint(Joint("sensor_joint", "fixed", "arm", "sensor", sensor_rotation))
    return _Design(u, "sensor", "sensor", {"theta2": 0.3, "d3": 0.5 * d3_max})


def _cartesian(travel: float = 1.0) -> _Design:
    travel = _positive("travel", travel)
    u = UrdfBuilder("cartesian")
    u.link("base", Shape("box", (travel, 0.05, 0.05), (travel / 2, 0, 0), colour="dark"))
    u.joint(Joint("d1", "prismatic", "base", "slide_x", axis=(1, 0, 0), limits=(0.0, travel)))
    u.link("slide_x", rod((0, 0, 0), (0, travel, 0), 0.02, "blue"))
    u.joint(Joint("d2", "prismatic", "slide_x", "slide_y", axis=(0, 1, 0), limits=(0.0, travel)))
    u.link("slide_y", rod((0, 0, 0), (0, 0, travel), 0.02, "blue"))
    u.joint(Joint("d3", "prismatic", "slide_y", "slide_z", axis=(0, 0, 1), limits=(0.0, travel)))
    u.link("slide_z", Shape("box", (0.06, 0.06, 0.06), colour="orange"))
    u.joint(Joint("theta4", "revolute", "slide_z", "wrist1", axis=(0, 0, 1)))
    u.joint(Joint("theta5", "revolute", "wrist1", "wrist2", axis=(0, 1, 0), limits=(-_PI / 2, _PI / 2)))
    u.joint(Joint("theta6", "revolute", "wrist2", "wrist3", axis=(1, 0, 0)))
    u.link("wrist3", rod((0, 0, 0), (0.1, 0, 0), 0.015, "green"))
    u.joint(Joint("tcp_joint", "fixed", "wrist3", "tcp"))
    return _Design(u, "tcp", "tcp", {"d1": travel / 2, "d2": travel / 2, "d3": travel / 2, "theta5": 0.3})


def _planar_polar(l: float = 0.2, d2_min: float = 0.05, d2_max: float = 1.0) -> _Design:  # noqa: E741
    l, d2_min, d2_max = _positive("l", l), _positive("d2_min", d2_min), _positive("d2_max", d2_max)  # noqa: E741
    if d2_min >= d2_max:
        raise InputError(f"d2_min ({d2_min}) must be below d2_max ({d2_max})")
    u = UrdfBuilder("planar_polar")
    u.link("base", Shape("cylinder", (0.04, 0.04), colour="dark"))
    u.joint(Joint("theta1", "revolute", "base", "link1"))
    u.link("link1", rod((0, 0, 0), (0.05, 0, 0), 0.015, "dark"))
    u.joint(Joint("d2", "prismatic", "link1", "link2", axis=(1, 0, 0), limits=(d2_min, d2_max)))
    u.link("link2", rod((-0.3, 0, 0), (0, 0, 0), 0.015, "blue"))
    u.joint(Joint("sensor_joint", "fixed", "link2", "sensor"))
    u.joint(Joint("theta3", "revolute", "link2", "link3"))
    u.link("link3", rod((0, 0, 0), (l, 0, 0), 0.012, "orange"))
    u.joint(Joint("tcp_joint", "fixed", "link3", "tcp", xyz=(l, 0, 0)))
    return _Design(u, "tcp", "sensor", {"d2": min(max(0.4, d2_min), d2_max), "theta3": 0.5})


def _scara_chain(name: str, l1: float, l2: float, l3: float, theta2_limits: tuple[float, float]) -> _Design:
    l1, l2, l3 = _positive("l1", l1), _positive("l2", l2), _positive("l3", l3)
    u = UrdfBuilder(name)
    u.link("base", rod((0, 0, -0.3), (0, 0, 0), 0.04, "dark"))
    u.joint(Joint("theta1", "revolute", "base", "link1", limits=(-_PI, _PI)))
    u.link("link1", rod((0, 0, 0), (l1, 0, 0), 0.03, "blue"))
    u.joint(Joint("theta2", "revolute", "link1", "link2", xyz=(l1, 0, 0), limits=theta2_limits))
    u.link("link2", rod((0, 0, 0), (l2, 0, 0), 0.025, "blue"))
    u.joint(Joint("sensor_joint", "fixed", "link2", "sensor", xyz=(l2, 0, 0)))
    u.joint(Joint("d", "prismatic", "link2", "quill", xyz=(l2, 0, 0), limits=(-0.2, 0.0)))
    u.link("quill", rod((0, 0, 0), (0, 0, 0.2), 0.012, "grey"))
    u.joint(Joint("theta3", "revolute", "quill", "tool"))
    u.link("tool", rod((0, 0, 0), (l3, 0, 0), 0.01, "orange"))
    u.joint(Joint("tcp_joint", "fixed", "tool", "tcp", xyz=(l3, 0, 0)))
    theta2 = min(max(1.0, theta2_limits[0]), theta2_limits[1])
    return _Design(u, "tcp", "sensor", {"theta2": theta2, "d": -0.1, "theta3": 0.5})


def _scara(l1: float = 0.4, l2: float = 0.4, l3: float = 0.4) -> _Design:
    return _scara_chain("scara", l1, l2, l3, (-_PI, _PI))


def _hirata_arh300(l1: float = 0.325, l2: float = 0.275, l3: float = 0.05) -> _Design:
    return _scara_chain("hirata_arh300", l1, l2, l3, (25 * _DEG, 145 * _DEG))


def _spherical_6dof(l: float = 0.1, d3_min: float = 0.3, d3_max: float = 0.8) -> _Design:  # noqa: E741
    l, d3_min, d3_max = _positive("l", l), _positive("d3_min", d3_min), _positive("d3_max", d3_max)  # noqa: E741
    if d3_min >= d3_max:
        raise InputError(f"d3_min ({d3_min}) must be below d3_max ({d3_max})")
    u = UrdfBuilder("spherical_6dof")
    u.link("base", Shape("cylinder", (0.07, 0.1), colour="dark"))
    u.joint(Joint("theta1", "revolute", "base", "turret"))
    u.joint(Joint("theta2", "revolute", "turret", "boom", axis=(0, 1, 0), limits=(-_PI / 2, _PI / 2)))
    u.link("boom", Shape("sphere", (0.06,), colour="blue"))
    u.joint(Joint("d3", "prismatic", "boom", "arm", axis=(1, 0, 0), limits=(d3_min, d3_max)))
    u.link("arm", rod((-d3_min, 0, 0), (0, 0, 0), 0.025, "blue"))
    # P: sensor on link 3, z radial (arm +x), x along the theta2 axis (arm +y), y = z × x.
    sensor_rotation = np.column_stack([[0, 1, 0], [0, 0, 1], [1, 0, 0]]).astype(float)
    u.joint(Joint("sensor_joint", "fixed", "arm", "sensor", sensor_rotation))
    u.joint(Joint("theta4", "revolute", "arm", "wrist1", sensor_rotation, axis=(0, 0, 1)))
    u.joint(Joint("theta5", "revolute", "wrist1", "wrist2", axis=(1, 0, 0), limits=(-_PI / 2, _PI / 2)))
    u.link("wrist2", Shape("sphere", (0.03,), colour="grey"))
    u.joint(Joint("theta6", "revolute", "wrist2", "wrist3", axis=(0, 0, 1)))
    u.link("wrist3", rod((0, 0, 0), (0, 0, l), 0.012, "orange"))
    u.joint(Joint("tcp_joint", "fixed", "wrist3", "tcp", xyz=(0, 0, l)))
    u.joint(Joint("wrist_centre_joint", "fixed", "wrist3", "wrist_centre"))  # P, on the last link
    return _Design(u, "tcp", "sensor", {"theta2": 0.3, "d3": (d3_min + d3_max) / 2, "theta5": 0.5})


# Barker's table: (alpha_i, a_i, r_i, offset_i, limit_i in degrees) with symbolic lengths.
def _barker_arm(
    no: float = 0.6604,
    es: float = 0.4318,
    sn: float = 0.1491,
    we: float = 0.4331,
    hw: float = 0.0563,
    alpha3: float = _PI / 2,
    a3: float = 0.0,
    r3: float = 0.0,
) -> _Design:
    no, es, we, hw = (_positive(n, v) for n, v in (("no", no), ("es", es), ("we", we), ("hw", hw)))
    sn, alpha3, a3, r3 = (_finite(n, v) for n, v in (("sn", sn), ("alpha3", alpha3), ("a3", a3), ("r3", r3)))
    table = [  # alpha, a, r, theta offset, limit (deg)
        (_PI / 2, 0.0, no, _PI, 160.0),
        (0.0, es, sn, _PI / 2, 165.0),
        (alpha3, a3, r3, _PI / 2, 135.0),
        (_PI / 2, 0.0, we, _PI, 135.0),
        (_PI / 2, 0.0, 0.0, _PI, 105.0),
        (0.0, 0.0, hw, 0.0, 270.0),
    ]
    u = UrdfBuilder("barker_arm")
    u.link("frame0", Shape("cylinder", (0.08, 0.1), (0, 0, 0.05), colour="dark"))
    parent, rotation, xyz = "frame0", None, (0.0, 0.0, 0.0)
    colours = ["dark", "blue", "blue", "orange", "grey", "green"]
    for i, (alpha, a, r, offset, limit) in enumerate(table, start=1):
        link = f"link{i}"
        u.joint(Joint(f"theta{i}", "revolute", parent, link, rotation, xyz, limits=(-limit * _DEG, limit * _DEG)))
        # DH: frame i = Rz(theta'_i) Tz(r_i) Tx(a_i) Rx(alpha_i) in frame i-1 (Barker eq. 1).
        turn = axis_rotation("z", offset)
        end = turn @ np.array([a, 0.0, r])
        u.link(link, rod((0, 0, 0), (0, 0, r), 0.03, colours[i - 1]), rod((0, 0, r), end, 0.03, colours[i - 1]))
        parent, rotation, xyz = link, turn @ axis_rotation("x", alpha), tuple(end)
    u.joint(Joint("hand_joint", "fixed", "link6", "hand", rotation, xyz))
    # The wrist centre: frames 4 and 5 meet at the origin of link 6's joint; hand axes.
    u.joint(Joint("wrist_centre_joint", "fixed", "link6", "wrist_centre", rotation))
    return _Design(u, "wrist_centre", "hand", {"theta2": 0.3, "theta3": 0.8, "theta5": 0.6})


_GENERATORS: dict[str, Callable[..., _Design]] = {
    "two_link_planar": _two_link_planar,
    "cylindrical": _cylindrical,
    "spherical": _spherical,
    "cartesian": _cartesian,
    "planar_polar": _planar_polar,
    "scara": _scara,
    "hirata_arh300": _hirata_arh300,
    "spherical_6dof": _spherical_6dof,
    "barker_arm": _barker_arm,
}

ROBOT_NAMES: tuple[str, ...] = tuple(_GENERATORS)
"""The papers' robots this module builds, by name (each also a function of its own)."""


def _generator(name: str) -> Callable[..., _Design]:
    generator = _GENERATORS.get(check_name(name, "robot name"))
    if generator is None:
        raise InputError(f"unknown paper robot {name!r}." + choices_hint(name, ROBOT_NAMES))
    return generator


def parameters(name: str) -> dict[str, float]:
    """The keyword arguments of a robot generator with their default (paper) values."""
    signature = inspect.signature(_generator(name))
    return {key: p.default for key, p in signature.parameters.items()}


def _generate(name: str, lengths: dict[str, float]) -> _Design:
    generator = _generator(name)
    unknown = sorted(set(lengths) - set(parameters(name)))
    if unknown:
        raise InputError(f"{name} has no parameter(s) {unknown}; its parameters: {', '.join(parameters(name))}")
    return generator(**lengths)


def urdf(name: str, **lengths: float) -> str:
    """The URDF text of a papers' robot with the given lengths (defaults: the paper's)."""
    return _generate(name, lengths).urdf.text()


def build(name: str, *, tip: str | None = None, sensor: str | None = None, **lengths: float) -> Robot:
    """A papers' robot as a :class:`Robot`, with the paper's tip and sensor unless overridden."""
    design = _generate(name, lengths)
    return robot_from_urdf(
        design.urdf.text(),
        label=name,
        tip=tip or design.tip,
        sensor=sensor or design.sensor,
        name=name,
        home_values=design.home,
    )


def two_link_planar(*, tip: str | None = None, sensor: str | None = None, **lengths: float) -> Robot:
    """Two-link planar arm of Fig. 1 (eq. 5-12): l1, l2."""
    return build("two_link_planar", tip=tip, sensor=sensor, **lengths)


def cylindrical(*, tip: str | None = None, sensor: str | None = None, **lengths: float) -> Robot:
    """Cylindrical arm theta1, d2, d3 (eq. 13): strokes d2_max, d3_max."""
    return build("cylindrical", tip=tip, sensor=sensor, **lengths)


def spherical(*, tip: str | None = None, sensor: str | None = None, **lengths: float) -> Robot:
    """Spherical arm of Fig. 2, theta1, theta2, d3 (eq. 14-16): stroke d3_max."""
    return build("spherical", tip=tip, sensor=sensor, **lengths)


def cartesian(*, tip: str | None = None, sensor: str | None = None, **lengths: float) -> Robot:
    """Cartesian arm with a wrist whose three axes meet at the TCP (the ideal of §3): travel."""
    return build("cartesian", tip=tip, sensor=sensor, **lengths)


def planar_polar(*, tip: str | None = None, sensor: str | None = None, **lengths: float) -> Robot:
    """Planar polar robot of Fig. 4 (eq. 55-58): l (default 0.2), stroke d2_min .. d2_max."""
    return build("planar_polar", tip=tip, sensor=sensor, **lengths)


def scara(*, tip: str | None = None, sensor: str | None = None, **lengths: float) -> Robot:
    """SCARA of Fig. 7 (eq. 59-63): l1, l2, l3 (default 0.4 each; l3 the tool length)."""
    return build("scara", tip=tip, sensor=sensor, **lengths)


def hirata_arh300(*, tip: str | None = None, sensor: str | None = None, **lengths: float) -> Robot:
    """Hirata ARH-300 SCARA (§5.2): l2 = 0.275, 25° <= theta2 <= 145°, tool length l3."""
    return build("hirata_arh300", tip=tip, sensor=sensor, **lengths)


def spherical_6dof(*, tip: str | None = None, sensor: str | None = None, **lengths: float) -> Robot:
    """Six-DOF spherical robot of Fig. 11 (eq. 70-73): tool length l beyond P, d3 range."""
    return build("spherical_6dof", tip=tip, sensor=sensor, **lengths)


def barker_arm(*, tip: str | None = None, sensor: str | None = None, **lengths: float) -> Robot:
    """Barker's six-joint arm (appendix A): no, es, sn, we, hw, alpha3, a3, r3."""
    return build("barker_arm", tip=tip, sensor=sensor, **lengths)


def write_urdfs(folder: str | os.PathLike[str]) -> list[Path]:
    """Write every papers' robot, with the papers' values, as ``folder/NAME.urdf``."""
    target = check_output_folder(folder, "URDF folder")
    written = []
    for name in ROBOT_NAMES:
        path = target / f"{name}.urdf"
        path.write_text(urdf(name), encoding="utf-8")
        written.append(path)
    return written
