"""A :class:`~pinrate.control.controller.Controller`'s options as the other modules see them:
the defaults of its twist saturation, and their names, read off the class's signature once
(this module sits below the controller: it is given the class)."""

from __future__ import annotations

import inspect

MAX_LINEAR_SPEED = 0.5
"""Default speed limit of the commanded TCP velocity (m/s)."""

MAX_ANGULAR_SPEED = 1.0
"""Default speed limit of the commanded angular velocity (rad/s)."""

_OPTIONS_OF: dict[type, tuple[str, ...]] = {}


def option_names(kind: type) -> tuple[str, ...]:
    """The parameters of a Controller class (a subclass's own included), whose coverage by
    the compiled core is looked up by name."""
    if kind not in _OPTIONS_OF:
        _OPTIONS_OF[kind] = tuple(inspect.signature(kind).parameters)
    return _OPTIONS_OF[kind]


__all__ = ["MAX_ANGULAR_SPEED", "MAX_LINEAR_SPEED", "option_names"]
