"""PNG pictures of the convergence analysis (matplotlib, no display needed)."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only: no display, no GUI toolkit

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import LinearSegmentedColormap, LogNorm

from ..control.trajectory import Trajectory
from ..errors import InputError
from .regions import RegionMap
from .sweeps import Sweep

RHO_RANGE = (0.01, 100.0)  # colour scale of ρ (log), 1 in the middle
CONVERGING = "#2ca02c"
DIVERGING = "#d62728"
# Green below ρ = 1, red above, pale at 1: the ρ = 1 contour is the boundary of the paper's figures.
RHO_COLOURS = LinearSegmentedColormap.from_list("rho", ["#00441b", "#41ab5d", "#f7f7f7", "#ef3b2c", "#67000d"])


def _angle_like(values: np.ndarray) -> bool:
    return float(values.max() - values.min()) > 1.5  # radians, not metres (a heuristic for labels)


def _axis(values: np.ndarray, joint: str) -> tuple[np.ndarray, str]:
    if _angle_like(values):
        return np.degrees(values), f"{joint} (deg)"
    return values, f"{joint} (m)"


def region_map_png(region: RegionMap, path: Path, *, title: str = "") -> Path:
    """ρ over two joints (log colour scale, 1 in the middle) with the ρ = 1 contour."""
    x, x_label = _axis(region.x, region.joints[0])
    y, y_label = _axis(region.y, region.joints[1])
    singular = ~np.isfinite(region.spectral_radius)
    radius = np.clip(np.where(singular, RHO_RANGE[1], region.spectral_radius), *RHO_RANGE)
    figure, axes = plt.subplots(figsize=(7, 5.5), dpi=110)
    image = axes.pcolormesh(x, y, radius, cmap=RHO_COLOURS, norm=LogNorm(*RHO_RANGE), shading="auto")
    # The ρ = 1 contour of the finite part only: a singular row would draw two spurious lines.
    contour = axes.contour(x, y, np.ma.masked_where(singular, radius), levels=[1.0], colors="black", linewidths=1.8)
    if singular.any():  # A or W not invertible: G is undefined there, drawn apart from large ρ
        axes.pcolormesh(
            x, y, np.ma.masked_where(~singular, np.ones_like(radius)), cmap="Greys", vmin=0, vmax=1.6, shading="auto"
        )
        axes.plot([], [], "s", color="0.45", label="A or W singular (G undefined)")
        axes.legend(loc="upper right", fontsize=8)
    axes.clabel(contour, fmt={1.0: "ρ = 1"}, fontsize=9)
    colour_bar = figure.colorbar(image, ax=axes)
    colour_bar.set_label("spectral radius ρ of G (converges where < 1)")
    axes.set_xlabel(x_label)
    axes.set_ylabel(y_label)
    axes.set_title(title or "ρ(G) over two joints")
    figure.tight_layout()
    figure.savefig(path)
    plt.close(figure)
    return path


def workspace_png(positions: np.ndarray, spectral_radius: np.ndarray, path: Path, *, title: str = "") -> Path:
    """TCP positions of sampled configurations, green where ρ < 1 and red elsewhere (top and side views)."""
    converging = np.asarray(spectral_radius) < 1.0
    figure, (top, side) = plt.subplots(1, 2, figsize=(11, 5), dpi=110)
    for axes, (i, j), labels in ((top, (0, 1), ("x (m)", "y (m)")), (side, (0, 2), ("x (m)", "z (m)"))):
        for mask, colour, label in ((converging, CONVERGING, "ρ < 1"), (~converging, DIVERGING, "ρ ≥ 1")):
            axes.scatter(positions[mask, i], positions[mask, j], s=4, c=colour, alpha=0.6, label=label, linewidths=0)
        axes.set_xlabel(labels[0])
        axes.set_ylabel(labels[1])
        axes.set_aspect("equal", adjustable="datalim")
        axes.grid(alpha=0.3)
    top.set_title("top view")
    side.set_title("side view")
    top.legend(loc="best", markerscale=4)
    figure.suptitle(title or "TCP positions")
    figure.tight_layout()
    figure.savefig(path)
    plt.close(figure)
    return path


def sweep_png(sweep: Sweep, path: Path, *, title: str = "") -> Path:
    """The converging share against the parameter (the paper's Fig. 10), the limit marked."""
    figure, axes = plt.subplots(figsize=(7, 4.5), dpi=110)
    axes.fill_between(
        sweep.values, 100 * sweep.low, 100 * sweep.high, color=CONVERGING, alpha=0.2, label="95 % interval"
    )
    axes.plot(sweep.values, 100 * sweep.fraction, "o-", color=CONVERGING, label="share with ρ < 1")
    if sweep.limit is not None and math.isfinite(sweep.limit):
        axes.axvline(
            sweep.limit,
            color="black",
            linestyle="--",
            label=f"{sweep.limit_kind} {sweep.parameter} for ρ < 1 everywhere: {sweep.limit:.4g}",
        )
    axes.set_xlabel(sweep.parameter)
    axes.set_ylabel("work volume with ρ < 1 (%)")
    axes.set_ylim(min(95.0, 100 * float(sweep.low.min())) - 2, 101)
    axes.grid(alpha=0.3)
    axes.legend(loc="best")
    axes.set_title(title or f"convergence against {sweep.parameter}")
    figure.tight_layout()
    figure.savefig(path)
    plt.close(figure)
    return path


def plant_tracking_png(trajectory: Trajectory, joint_names: tuple[str, ...], path: Path, *, title: str = "") -> Path:
    """A run on a plant (``trajectory.plant``): each joint's commanded rate (line) and the
    rate the plant measured (dots) against time, steps with a saturated actuator shaded, and
    the tip's tracking error (mm) below."""
    record = trajectory.plant
    if record is None:
        raise InputError("the trajectory was not run on a plant: it has no measured rates")
    time = np.arange(trajectory.steps) * trajectory.dt
    figure, (rates, tracking) = plt.subplots(
        2, 1, figsize=(8, 6), dpi=110, sharex=True, gridspec_kw={"height_ratios": [3, 1]}
    )
    for joint, name in enumerate(joint_names):
        (line,) = rates.plot(time, trajectory.joint_rates[:, joint], linewidth=1.4, label=name)
        rates.plot(time, record.measured_rates[:, joint], ".", markersize=2.5, color=line.get_color())
    saturated = record.saturated.any(axis=1)
    if saturated.any():
        rates.fill_between(
            time, 0, 1, where=saturated, transform=rates.get_xaxis_transform(), color="0.85", label="actuator saturated"
        )
    rates.set_ylabel("joint rate (rad/s or m/s)\nline: commanded   dots: measured")
    rates.legend(fontsize=7, ncol=3, loc="upper right")
    rates.set_title(title or f"{record.name}: commanded and measured joint rates")
    # Log scale: the first steps' jump from rest would flatten the rest of the run.
    tracking.semilogy(time, np.maximum(record.tracking_error * 1e3, 1e-9), color="black", linewidth=1.2)
    tracking.set_ylabel("tip tracking\nerror (mm)")
    tracking.set_xlabel("time (s)")
    figure.tight_layout()
    figure.savefig(path)
    plt.close(figure)
    return path
