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

The data come from :mod:`.structure`, :mod:`.design`, :mod:`.regions` and :mod:`.sweeps`;
:mod:`.plots` draws them and :func:`write_report` writes the Markdown + PNG report.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..checks import check_output_folder
from ..errors import InputError
from ..kinematics.manipulator import Robot
from ..kinematics.partition import Partition, partition_for
from ..theorem.sampling import ConvergenceSample, sample_convergence
from . import design, plots
from .regions import RegionMap, region_map, tcp_positions
from .structure import BlockStructure, block_structure
from .sweeps import Sweep


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

    def explain_share(self) -> list[str]:
        """Why ρ < 1 nowhere, when that is so: which block is singular at every sampled
        configuration and the rank it has there, or that the error map keeps an eigenvalue 1
        (a direction never corrected), or that ρ > 1 everywhere."""
        radii = self.sample.spectral_radius
        if not radii.size or np.any(radii < 1.0):
            return []
        lines = ["**Why ρ < 1 nowhere:**", ""]
        if np.all(~np.isfinite(radii)):
            lines += [f"- {line}" for line in _singular_blocks(self.robot, self.partition, self.sample.q)]
        elif np.all(radii == 1.0):
            lines.append(
                "- the error map has an eigenvalue 1 at every sampled configuration: some direction is never "
                "corrected to first order (typically a linear row the arm block cannot produce, the wrist serving "
                "only the angular rows); the test is inconclusive, and `exact` is the algorithm for this partition"
            )
        else:
            lines.append(
                f"- ρ > 1 at every finite sample (smallest {np.min(radii):.3g}): MCA1/2/3 diverge in the whole "
                "work volume for this partition and sensor; use `exact`, or another sensor frame or partition"
            )
        return [*lines, ""]

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
            *(
                (
                    "G (MCA1's matrix) and H (MCA2's) share their non-zero eigenvalues, so the share is the same for",
                    "MCA1, MCA2 and MCA3.",
                )
                if self.partition.resolve(self.robot).square
                else (
                    "A or W is not square, so the Theorem does not apply as stated: ρ is that of MCA1's error map",
                    "I - J K (pinrate.solvers.error_map), which reduces to ρ(G) for square blocks.",
                )
            ),
            "",
            *self.explain_share(),
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


SINGULAR_PROBES = 5
"""Sampled configurations examined to say why a block is singular everywhere."""


def _singular_blocks(robot: Robot, partition: Partition, configurations: np.ndarray) -> list[str]:
    """For square blocks A and W singular at every one of the first configurations: the rank
    each has there, and which joints and rows it relates."""
    index = partition.resolve(robot)
    probes = configurations[:SINGULAR_PROBES]
    jacobians = [robot.jacobian(q)[np.ix_(index.rows, index.columns)] for q in probes]
    arm = len(index.arm_columns)
    lines = []
    for name, rows, columns, joints, axes in (
        ("A", slice(0, index.m), slice(0, arm), partition.arm, f"linear {partition.linear}"),
        ("W", slice(index.m, None), slice(arm, None), partition.wrist, f"angular {partition.angular}"),
    ):
        blocks = [J[rows, columns] for J in jacobians]
        size = blocks[0].shape[0]
        if size == 0 or blocks[0].shape[0] != blocks[0].shape[1]:
            continue
        rank = max(int(np.linalg.matrix_rank(block)) for block in blocks)
        if rank < size:
            lines.append(
                f"{name} ({size}x{size}) has rank {rank} at every configuration examined: the joints "
                f"{', '.join(joints)} produce only {rank} independent {axes} directions at the sensor, so "
                f"{name}^-1 (eq. 24-25) does not exist; choose other joints or axes (--arm, --wrist, --linear, "
                "--angular) or the algorithm `exact`"
            )
    return lines or ["A or W is numerically singular at every sampled configuration (pinrate's singularity rule)"]


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
    partition = partition_for(robot, partition)
    sample = sample_convergence(
        robot, samples, partition=partition, rng=rng, workers=workers, scheduler=scheduler, progress=progress
    )
    region = (
        region_map(robot, joints=map_joints, points=points, partition=partition, workers=workers)
        if len(partition.joints) >= 2
        else None
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
    if not isinstance(report, Report):
        raise InputError(f"write_report takes the Report that analyze() returns, not {type(report).__name__}")
    out = check_output_folder(folder, "report folder")
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
