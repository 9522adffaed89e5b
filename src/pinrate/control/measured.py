"""The configuration a plant measured, as a controller may take it (the closed loops on a
plant: :func:`~pinrate.control.servo_loop.servo` with ``plant=``, the console's Teleop).

A real or simulated joint lags its command, so near a position limit it may stop a little past
it (a velocity servo of time constant T moving at q̇ comes to rest about q̇ T beyond where its
command stopped; a simulator's limit is a stiff spring, not a wall). :meth:`Controller.step`
refuses a q outside the limits it keeps (a step from there would have to snap the joint), so
the loop hands it the measured q with each joint that is past a limit by at most the plant's
``limit_tolerance`` put on that limit: the controller's view then differs from the measurement
by at most that tolerance, which the next measurement corrects, and the record keeps what was
measured. A joint past its limit by more is not the controller's to hide: the loop stops and
says which joint, where, and by how much."""

from __future__ import annotations

import numpy as np

from .controller import Controller


def onto_limits(
    controller: Controller, q: np.ndarray, tolerance: np.ndarray, *, clip: bool = False
) -> tuple[np.ndarray, str]:
    """(q for the controller, "" or the words naming each joint past a kept limit by more
    than its ``tolerance``; velocity order, rad or m). Joints past a limit by at most their
    tolerance are put on it (a copy of ``q``; ``q`` itself when nothing moved); with
    ``clip``, the joints past it by more too (for a loop that halts and goes on from there)."""
    if not controller.position_limits:
        return q, ""
    view = q
    beyond = []
    for limit in controller.joint_limits:
        value = float(q[limit.q_index])
        bound = limit.upper if value > limit.upper else limit.lower if value < limit.lower else value
        if bound == value:
            continue
        if abs(value - bound) > tolerance[limit.velocity]:
            beyond.append(
                f"{limit.joint} at {value:.6g}, {abs(value - bound):.3g} past its limit {bound:.6g} "
                f"(tolerance {tolerance[limit.velocity]:.3g})"
            )
            if not clip:
                continue
        if view is q:
            view = q.copy()
        view[limit.q_index] = bound
    return view, "; ".join(beyond)


__all__ = ["onto_limits"]
