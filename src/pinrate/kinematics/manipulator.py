"""A URDF manipulator as the user meets it: the kinematics of its tip and sensor frames
(:mod:`.kinematic_model`), a home inside every joint's limits and non-singular (:mod:`.home`),
its visual and collision geometry, and a picklable spec.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import PinrateError
from .home import find_home
from .kinematic_model import KinematicModel, not_a_robot
from .mimic import Mimic
from .partition import Partition


@dataclass(frozen=True)
class RobotSpec:
    """What a worker needs to rebuild a robot's kinematics: URDF text, tip, sensor, name
    (picklable; :func:`pinrate.kinematics.urdf.robot_from_spec` builds it)."""

    urdf_text: str
    tip: str
    sensor: str
    name: str


def check_robot(robot: object) -> Robot:
    """``robot`` if it is a :class:`Robot`; InputError otherwise (a name or a path included)."""
    if not isinstance(robot, Robot):
        raise not_a_robot(robot)
    return robot


class Robot(KinematicModel):
    """A Pinocchio model with a tip (TCP) frame and a sensor frame.

    Attributes:
        model, data: the Pinocchio model and its data (the data is scratch space reused by
            every call, so a Robot is not thread-safe; use one Robot per thread).
        tip: name of the frame whose origin is the TCP.
        tip_choice: how the tip was picked ("given", or how pinrate chose it).
        sensor: name of the frame whose axes twists are expressed in.
        joint_names: the moving joints, in velocity-vector order.
        reference_configurations: named configurations (from the SRDF, plus ``"home"``).
        home_choice: where :meth:`home` comes from (a reference, an SRDF state, a search, neutral).
        srdf_path: the SRDF read with the URDF (its disabled collision pairs, its poses), or None.
        hand_joints: the gripper and hand joints (zero-range, named like a hand part, mimic
            groups and prismatic joints at the end of the chain) that the default tip and the
            automatic partition leave out (:mod:`.frames`).
        arm_mimics: the mimic joints that follow an arm joint (parallelogram links), left out too.
        mimics: every mimic joint's relation to its leader, q_follower = m q_leader + o
            (:mod:`.mimic`; ``mimic`` maps a follower to its leader's name or its
            :class:`~.mimic.Mimic`): J folds the followers between the base and the tip into
            their leaders' columns, every step drives the followers, and :meth:`home` puts
            them on the relation (then inside their own limits).

    With ``search_home`` (the default), :meth:`home` is inside every joint's limits and
    non-singular whenever such a configuration exists (:func:`.home.find_home`): the first of
    ``home_candidates`` (label, q) that is, else one found near neutral. Without
    ``home_candidates``, a ``"home"`` in ``reference_configurations`` is the home as given;
    otherwise the candidates are the model's own reference configurations (an SRDF read with
    ``pinocchio.loadReferenceConfigurations``), ``home`` first, then by name. So a model built
    by hand (``pinrate.Robot(model)``) gets the home :func:`pinrate.load` gives a URDF file.
    """

    def __init__(
        self,
        model: pin.Model,
        *,
        tip: str | None = None,
        sensor: str | None = None,
        name: str = "",
        urdf_path: Path | None = None,
        urdf_text: str | None = None,
        package_dirs: Sequence[str] = (),
        reference_configurations: Mapping[str, np.ndarray] | None = None,
        mimic: Mapping[str, str | Mimic] | None = None,
        srdf_path: Path | None = None,
        search_home: bool = True,
        home_candidates: Sequence[tuple[str, np.ndarray]] | None = None,
    ) -> None:
        super().__init__(
            model, tip=tip, sensor=sensor, name=name, reference_configurations=reference_configurations, mimic=mimic
        )
        self._urdf_path = urdf_path
        self._urdf_text = urdf_text
        self._package_dirs = list(package_dirs)
        self.srdf_path = srdf_path if srdf_path is not None and srdf_path.is_file() else None
        self._geometry: dict[pin.GeometryType, pin.GeometryModel] = {}
        if search_home and (home_candidates is not None or "home" not in self.reference_configurations):
            candidates = self._model_references() if home_candidates is None else home_candidates
            q, self.home_choice = find_home(self, Partition.auto(self), candidates)
            self.reference_configurations["home"] = q

    def _model_references(self) -> list[tuple[str, np.ndarray]]:
        """The model's reference configurations (label, q): ``home`` first, the others by name."""
        references = {entry.key(): np.array(entry.data(), dtype=float) for entry in self.model.referenceConfigurations}
        return [
            (f"the model's reference configuration {key!r}", references[key])
            for key in sorted(references, key=lambda key: (key != "home", key))
            if references[key].shape == (self.nq,)
        ]

    def spec(self) -> RobotSpec:
        """A picklable recipe of this robot's kinematics (for worker processes and Dask)."""
        if self._urdf_text is None:
            raise PinrateError(f"robot {self.name!r} was built from a model, not URDF text: it has no spec")
        return RobotSpec(urdf_text=self._urdf_text, tip=self.tip, sensor=self.sensor, name=self.name)

    def __repr__(self) -> str:
        return f"Robot({self.name!r}, nq={self.nq}, nv={self.nv}, tip={self.tip!r}, sensor={self.sensor!r})"

    # ------------------------------------------------------------------ geometry
    @property
    def visual_model(self) -> pin.GeometryModel:
        """Visual geometries, loaded on first use; an empty model (with a warning) on failure."""
        return self._geometry_model(pin.GeometryType.VISUAL)

    @property
    def collision_model(self) -> pin.GeometryModel:
        """Collision geometries (the URDF's ``<collision>`` elements), loaded on first use; an
        empty model (with a warning) on failure. No pairs are set: see
        :mod:`pinrate.control.collision`."""
        return self._geometry_model(pin.GeometryType.COLLISION)

    def _geometry_model(self, kind: pin.GeometryType) -> pin.GeometryModel:
        if kind not in self._geometry:
            self._geometry[kind] = self._load_geometry(kind)
        return self._geometry[kind]

    def _load_geometry(self, kind: pin.GeometryType) -> pin.GeometryModel:
        what = "visual" if kind == pin.GeometryType.VISUAL else "collision"
        try:
            if self._urdf_path is None and self._urdf_text is not None:
                return pin.buildGeomFromUrdfString(self.model, self._urdf_text, kind, package_dirs=self._package_dirs)
            if self._urdf_path is not None:
                return pin.buildGeomFromUrdf(self.model, str(self._urdf_path), kind, package_dirs=self._package_dirs)
        except (RuntimeError, ValueError, OSError) as error:
            warnings.warn(f"{self.name}: {what} meshes not loaded ({error}); kinematics unaffected", stacklevel=3)
        return pin.GeometryModel()
