"""Convergence analysis of any robot: the report behind ``pinrate analyze``.

What a designer asks of the Theorem (Shoham & Koren §4-5), for any URDF:

1. the partition and the block structure: which entries of A, B, U, W vanish everywhere
   (B = 0: MCA2 is exact, eq. 22; U = 0: MCA1 is exact);
2. which joints the sensor-frame Jacobian does not depend on (§2);
3. the share of the work volume where ρ < 1, with a 95 % interval, and the worst places;
4. region maps: ρ over two joints with the others fixed (Fig. 5, 8, 12), and the TCP
   positions of sampled configurations coloured by converge/diverge;
5. design sweeps: the converging share against a robot parameter, and the parameter limit
   for convergence everywhere (Fig. 10, the Hirata rule, d2 / l > 2).

Everything here is data; :mod:`pinrate.plots` draws it and :func:`write_report` writes the
Markdown + PNG report.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import design
from .convergence import ConvergenceSample, sample_convergence, spectral_radius_at, wilson_interval
from .errors import InputError
from .partition import Partition
from .robot import Robot

_ZERO = 1e-9  # an entry is zero when below this times (1 + max |J|)
_SENSITIVITY_BASES = 24  # base configurations when ranking joints by their effect on ρ
_SENSITIVITY_STEPS = 9  # values of the moved joint per base configuration
_RHO_CLIP = 4.0  # ρ above this counts as 4 when ranking joints (poles would dominate)


@dataclass(frozen=True)
class BlockStructure:
    """Which entries of A, B, U, W are zero at every sampled configuration."""

    zero: dict[str, np.ndarray]  # block name -> bool mask of identically zero entries
    partition: Partition

    @property
    def B_is_zero(self) -> bool:
        return bool(self.zero["B"].all())

    @property
    def U_is_zero(self) -> bool:
        return bool(self.zero["U"].all())

    def lines(self) -> list[str]:
        """A sentence per block, and what the zero blocks mean."""
        axes = {
            "A": (self.partition.linear, self.partition.arm),
            "B": (self.partition.linear, self.partition.wrist),
            "U": (self.partition.angular, self.partition.arm),
            "W": (self.partition.angular, self.partition.wrist),
        }
        lines = []
        for name, mask in self.zero.items():
            rows, columns = axes[name]
            if mask.size == 0:
                lines.append(f"{name}: empty ({len(rows)}x{len(columns)})")
            elif mask.all():
                lines.append(f"{name}: identically zero ({mask.shape[0]}x{mask.shape[1]})")
            else:
                zeros = [f"({rows[i]}, {columns[j]})" for i, j in zip(*np.nonzero(mask), strict=True)]
                lines.append(f"{name}: {mask.shape[0]}x{mask.shape[1]}, zero entries: {', '.join(zeros) or 'none'}")
        if self.B_is_zero and self.zero["B"].size:
            lines.append("B = 0: the wrist axes meet at the TCP, so MCA2 is exact here (eq. 22).")
        if self.U_is_zero and self.zero["U"].size:
            lines.append("U = 0: the arm does not turn the tool, so MCA1 is exact here (§3).")
        return lines


def block_structure(
    robot: Robot, *, partition: Partition | None = None, samples: int = 64, rng: int = 11
) -> BlockStructure:
    """Zero patterns of A, B, U, W over ``samples`` random configurations (plus home)."""
    partition = Partition.auto(robot) if partition is None else partition
    configurations = np.vstack(
        [robot.home()[None, :], robot.sample_configurations(samples, rng, joints=partition.joints)]
    )
    magnitude = [np.abs(block) for block in partition.blocks(robot, robot.sensor_jacobian(configurations[0]))]
    for q in configurations[1:]:
        current = partition.blocks(robot, robot.sensor_jacobian(q))
        magnitude = [np.maximum(a, np.abs(b)) for a, b in zip(magnitude, current, strict=True)]
    scale = 1.0 + max((float(m.max()) for m in magnitude if m.size), default=0.0)
    return BlockStructure({name: m <= _ZERO * scale for name, m in zip("ABUW", magnitude, strict=True)}, partition)


# ---------------------------------------------------------------------- region maps
@dataclass(frozen=True)
class RegionMap:
    """ρ on a grid of two joints, the others at ``base``."""

    joints: tuple[str, str]
    x: np.ndarray  # values of joints[0] (nx,)
    y: np.ndarray  # values of joints[1] (ny,)
    spectral_radius: np.ndarray  # (ny, nx)
    base: np.ndarray  # the configuration the other joints are taken from

    @property
    def fraction(self) -> float:
        """Share of the grid with ρ < 1."""
        return float(np.mean(self.spectral_radius < 1.0))


def joint_sensitivity(robot: Robot, *, partition: Partition | None = None, rng: int = 5) -> dict[str, float]:
    """How much ρ changes when each partition joint moves alone (mean spread, ρ clipped at 4)."""
    partition = Partition.auto(robot) if partition is None else partition
    generator = np.random.default_rng(rng)
    bases = robot.sample_configurations(_SENSITIVITY_BASES, generator, joints=partition.joints)
    sensitivity = {}
    for joint in partition.joints:
        values = np.linspace(*robot.joint_range(joint), _SENSITIVITY_STEPS)
        configurations = np.repeat(bases, _SENSITIVITY_STEPS, axis=0)
        robot.set_joint_values(configurations, joint, np.tile(values, _SENSITIVITY_BASES))
        radii = np.minimum(spectral_radius_at(robot, configurations, partition=partition), _RHO_CLIP)
        sensitivity[joint] = float(np.mean(np.std(radii.reshape(_SENSITIVITY_BASES, _SENSITIVITY_STEPS), axis=1)))
    return sensitivity


def default_map_joints(robot: Robot, *, partition: Partition | None = None) -> tuple[str, str]:
    """The two partition joints ρ varies most with (ties: chain order)."""
    partition = Partition.auto(robot) if partition is None else partition
    if len(partition.joints) < 2:
        raise InputError(f"a region map needs two partition joints; {robot.name!r} has {list(partition.joints)}")
    sensitivity = joint_sensitivity(robot, partition=partition)
    ranked = sorted(partition.joints, key=lambda j: -sensitivity[j])[:2]
    return tuple(sorted(ranked, key=partition.joints.index))  # type: ignore[return-value]


def region_map(
    robot: Robot,
    *,
    joints: Sequence[str] | None = None,
    points: int = 121,
    partition: Partition | None = None,
    base: np.ndarray | None = None,
) -> RegionMap:
    """ρ over a ``points`` x ``points`` grid of two joints (default: the two ρ varies most with)."""
    partition = Partition.auto(robot) if partition is None else partition
    pair = tuple(joints) if joints is not None else default_map_joints(robot, partition=partition)
    if len(pair) != 2 or pair[0] == pair[1]:
        raise InputError(f"a region map needs two different joints, got {list(pair)}")
    for joint in pair:
        if joint not in partition.joints:
            raise InputError(f"joint {joint!r} is not in the partition; choose from {', '.join(partition.joints)}")
    base = robot.home() if base is None else robot.check_q(base)
    x = np.linspace(*robot.joint_range(pair[0]), points)
    y = np.linspace(*robot.joint_range(pair[1]), points)
    configurations = np.tile(base, (points * points, 1))
    grid_x, grid_y = np.meshgrid(x, y)
    robot.set_joint_values(configurations, pair[0], grid_x.ravel())
    robot.set_joint_values(configurations, pair[1], grid_y.ravel())
    radii = spectral_radius_at(robot, configurations, partition=partition).reshape(points, points)
    return RegionMap(joints=pair, x=x, y=y, spectral_radius=radii, base=base)


def tcp_positions(robot: Robot, configurations: np.ndarray) -> np.ndarray:
    """TCP positions (N, 3) in the world."""
    return np.array([robot.pose(q)[:3, 3] for q in configurations])


# ---------------------------------------------------------------------- sweeps
@dataclass(frozen=True)
class Sweep:
    """The converging share of the work volume against one robot parameter."""

    parameter: str
    values: np.ndarray
    fraction: np.ndarray
    low: np.ndarray  # 95 % interval
    high: np.ndarray
    worst: np.ndarray  # worst ρ on the dense grid at each value
    limit: float | None  # the parameter bound for ρ < 1 everywhere (None if none in range)
    limit_kind: str  # "largest", "smallest" or "none"


def sweep(
    factory: Callable[[float], Robot],
    parameter: str,
    low: float,
    high: float,
    *,
    steps: int = 12,
    samples: int = 4000,
    points: int = 61,
    rng: int = 0,
    tolerance: float = 1e-5,
    progress: bool | None = None,
) -> Sweep:
    """Fraction with ρ < 1 at ``steps`` values in [low, high], and the convergence limit.

    The limit is the largest (ρ grows with the parameter) or smallest (ρ shrinks with it)
    value whose worst ρ on a dense grid of the joints J depends on stays below 1, found by
    bisection (:func:`pinrate.design.largest_parameter`).
    """
    if not (math.isfinite(low) and math.isfinite(high)) or low >= high:
        raise InputError(f"sweep range {parameter}={low}:{high} must have low < high")
    from tqdm.auto import tqdm

    values = np.linspace(low, high, steps)
    fractions, lows, highs, worst = [], [], [], []
    for value in tqdm(
        values, desc=f"sweep {parameter}", disable=None if progress is None else not progress, leave=False
    ):
        robot = factory(float(value))
        sample = sample_convergence(robot, samples, rng=rng)
        count = int(np.sum(sample.spectral_radius < 1))
        fractions.append(sample.fraction)
        interval = wilson_interval(count, samples)
        lows.append(interval[0])
        highs.append(interval[1])
        worst.append(design.worst_spectral_radius(robot, points=points))
    worst_array = np.array(worst)
    converges_low, converges_high = worst_array[0] < 1, worst_array[-1] < 1
    limit: float | None
    if converges_low and not converges_high:
        limit, kind = design.largest_parameter(factory, low, high, points=points, tolerance=tolerance), "largest"
    elif converges_high and not converges_low:
        limit, kind = design.smallest_parameter(factory, low, high, points=points, tolerance=tolerance), "smallest"
    else:
        limit, kind = None, "none"
    return Sweep(parameter, values, np.array(fractions), np.array(lows), np.array(highs), worst_array, limit, kind)


def parse_sweep(text: str) -> tuple[str, float, float]:
    """'PARAM=LO:HI' -> (PARAM, LO, HI)."""
    try:
        name, bounds = text.split("=", 1)
        low, high = (float(v) for v in bounds.split(":", 1))
    except ValueError:
        raise InputError(f"--sweep takes PARAM=LO:HI (for example l3=0.01:0.2), got {text!r}") from None
    return name.strip(), low, high


# ---------------------------------------------------------------------- the report
@dataclass
class Report:
    """Everything ``pinrate analyze`` prints and writes."""

    robot: Robot
    partition: Partition
    structure: BlockStructure
    independent: tuple[str, ...]
    sample: ConvergenceSample
    region: RegionMap | None
    tcp: np.ndarray
    sweep: Sweep | None = None
    files: dict[str, Path] = field(default_factory=dict)

    def worst(self, count: int = 5) -> list[tuple[float, np.ndarray]]:
        """The sampled configurations with the largest ρ."""
        order = np.argsort(-np.where(np.isfinite(self.sample.spectral_radius), self.sample.spectral_radius, 1e300))
        return [(float(self.sample.spectral_radius[i]), self.sample.q[i]) for i in order[:count]]

    def markdown(self) -> str:
        sample = self.sample
        low, high = sample.interval
        lines = [
            f"# Convergence analysis: {self.robot.name}",
            "",
            f"Tip `{self.robot.tip}`, sensor `{self.robot.sensor}`; {self.robot.nv} joints in the model.",
            "",
            "## Partition",
            "",
            "```",
            str(self.partition),
            "```",
            "",
            "Joints of the tip's chain that move the tip; twist components the joints never produce are",
            "dropped; the wrist is the last min(k, n - m) joints (the contract's automatic rule).",
            "",
            "## Block structure",
            "",
            *[f"- {line}" for line in self.structure.lines()],
            "",
            "## Joints the sensor-frame Jacobian does not depend on",
            "",
            (
                "- " + ", ".join(f"`{j}`" for j in self.independent) + ": their encoders are not needed to compute "
                "rates (Shoham & Koren §2)"
            )
            if self.independent
            else "- none",
            "",
            "## The Theorem over the work volume",
            "",
            f"{sample.spectral_radius.size:,} configurations uniform in the joint limits: ρ < 1 on "
            f"**{100 * sample.fraction:.2f} %** (95 % interval {100 * low:.2f} .. {100 * high:.2f} %).",
            "G (MCA1's matrix) and H (MCA2's) share their non-zero eigenvalues, so the share is the same for",
            "MCA1, MCA2 and MCA3.",
            "",
            "Worst configurations sampled:",
            "",
            "| ρ | q |",
            "|---|---|",
            *[f"| {rho:.3g} | {np.array2string(q, precision=3, max_line_width=200)} |" for rho, q in self.worst()],
        ]
        if self.region is not None:
            lines += [
                "",
                "## Region map",
                "",
                f"ρ over `{self.region.joints[0]}` x `{self.region.joints[1]}`, the other joints at home; "
                f"ρ < 1 on {100 * self.region.fraction:.1f} % of the map.",
            ]
        for name, path in self.files.items():
            lines += ["", f"![{name}]({path.name})"]
        if self.sweep is not None:
            s = self.sweep
            lines += [
                "",
                f"## Sweep of `{s.parameter}`",
                "",
                "| value | ρ < 1 (%) | 95 % interval | worst ρ (grid) |",
                "|---|---|---|---|",
            ]
            lines += [
                f"| {v:.4g} | {100 * f:.2f} | {100 * lo:.2f} .. {100 * hi:.2f} | {w:.3g} |"
                for v, f, lo, hi, w in zip(s.values, s.fraction, s.low, s.high, s.worst, strict=True)
            ]
            if s.limit is not None:
                lines += [
                    "",
                    f"**{s.limit_kind.capitalize()} `{s.parameter}` with ρ < 1 everywhere: {s.limit:.6g}** "
                    "(bisection on a dense joint grid).",
                ]
            else:
                lines += ["", "No convergence limit inside the range (ρ < 1 everywhere at both ends, or at neither)."]
        return "\n".join(lines) + "\n"


def analyze(
    robot: Robot,
    *,
    samples: int = 100_000,
    partition: Partition | None = None,
    rng: int = 0,
    map_joints: Sequence[str] | None = None,
    points: int = 121,
    workers: int = 1,
    scheduler: object = None,
    progress: bool | None = None,
    tcp_samples: int = 3000,
) -> Report:
    """Compute the whole report (no files written; see :func:`write_report`)."""
    partition = Partition.auto(robot) if partition is None else partition
    sample = sample_convergence(
        robot, samples, partition=partition, rng=rng, workers=workers, scheduler=scheduler, progress=progress
    )
    region = (
        region_map(robot, joints=map_joints, points=points, partition=partition) if len(partition.joints) >= 2 else None
    )
    shown = min(tcp_samples, sample.q.shape[0])
    return Report(
        robot=robot,
        partition=partition,
        structure=block_structure(robot, partition=partition),
        independent=design.independent_joints(robot, partition=partition),
        sample=sample,
        region=region,
        tcp=tcp_positions(robot, sample.q[:shown]),
    )


def write_report(report: Report, folder: str | Path) -> Path:
    """Write ``report.md`` and its PNGs into ``folder``; returns the Markdown path."""
    from . import plots

    out = Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    name = report.robot.name
    if report.region is not None:
        report.files["region map"] = plots.region_map_png(
            report.region, out / f"{name}-region-map.png", title=f"{name}: ρ(G) over two joints"
        )
    report.files["work volume"] = plots.workspace_png(
        report.tcp,
        report.sample.spectral_radius[: report.tcp.shape[0]],
        out / f"{name}-work-volume.png",
        title=f"{name}: TCP positions, ρ < 1 or not",
    )
    if report.sweep is not None:
        report.files["sweep"] = plots.sweep_png(
            report.sweep,
            out / f"{name}-sweep-{report.sweep.parameter}.png",
            title=f"{name}: share with ρ < 1 against {report.sweep.parameter}",
        )
    path = out / "report.md"
    path.write_text(report.markdown(), encoding="utf-8")
    return path
