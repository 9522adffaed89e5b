"""One control step, the seam that the servo and teleoperation share.

Each step at configuration q (Shoham & Koren §2, Fig. 3) is a pipeline of stages, each a
module of its own, in this order:

1. **observe**: kinematics at q, one Pinocchio pass: the sensor-frame Jacobian J (eq. 1-8),
   the tip and sensor poses, and ρ of the smaller of G and H (eq. 32, 50) — an
   :class:`~.observation.Observation`;
2. **command → twist**: a twist is taken as it is; a :class:`PoseGoal` commands ``gain``
   times the pose error, position error R_s^T (p_target - p_tip) and rotation error
   R_s^T log3(R_target R_tip^T); a :class:`JointJog` or an :class:`Uncoupled` command
   names joint rates instead (:mod:`.joint_space`, :mod:`.uncoupled`);
3. **bound**: the whole twist is scaled down by one factor, the largest that keeps its
   linear part within ``max_linear_speed`` and its angular part within ``max_angular_speed``
   (the commanded screw keeps its direction); what the partition cannot make of it is said
   (:mod:`.reach`);
4. **plan**: where a cheap conditioning bound says the step may be in the singular region,
   the wrist rule and the ``singularity=`` strategy decide how it solves
   (:mod:`.singularity`: one module per strategy); Barker's auxiliary elbow takes the step
   near full extension;
5. **solve**: the algorithm (:mod:`pinrate.solvers`), or the plan's inversion, turns the
   twist into joint rates; a posture task adds null-space motion (:mod:`.posture`); which
   solve runs is :mod:`.solve`'s choice;
6. **limits**, in a fixed order (:mod:`.limits`): position (joints held at a limit, the
   others solved again), then the decelerating strategies' one-step look-ahead, velocity
   (one scale factor), acceleration (a blend from the last rates), self-collision
   (:mod:`.collision`); from velocity on, every step ends alike (:mod:`.finish`);
7. **integrate**: q over dt on the configuration space (``pin.integrate``), clamped to the
   limits (a guard against rounding: the position stage already keeps q inside);
8. **rank** the conditions met: the :class:`~.observation.Step`'s status is the most severe
   (:mod:`.status`).
"""

from __future__ import annotations

import numpy as np

from ..checks import check_positive, check_vector
from ..compiled import CoreServo
from ..errors import InputError, SingularBlockError
from ..kinematics.manipulator import Robot
from ..kinematics.partition import Partition, partition_for
from ..kinematics.spatial import pose_error, saturate_twist
from ..solvers.conditioning import row_scale
from ..solvers.registry import check_algorithm
from . import compiled_twin
from .collision import monitor_for
from .commands import JointJog, PoseGoal, Uncoupled
from .context import StepContext
from .core_step import CorePath, Sight
from .elbow import Elbow
from .finish import Finish
from .joint_space import JointSpace
from .limits import AccelerationLimits, PositionLimits, VelocityLimits, per_joint
from .observation import Observation, Step, error_norms
from .options import MAX_ANGULAR_SPEED, MAX_LINEAR_SPEED, option_names
from .posture import PostureTask
from .reach import out_of_reach
from .robot_facts import Limit, robot_facts
from .singular_region import Conditioning, check_strategy, check_thresholds, measured_blocks
from .singularity import RULES, SINGULAR_THRESHOLD, SLOW_THRESHOLD, STRATEGIES, WRIST_STRATEGIES, plan_step
from .singularity.auxiliary_elbow import AuxiliaryElbow
from .singularity.decelerate import decelerate, watched
from .solve import TwistSolver
from .status import Status


class Controller:
    """The resolved-rate control step of a robot (one Robot per controller and thread).

    Args:
        robot: the robot; its tip and sensor frames fix what twists mean.
        algorithm: a name of :data:`pinrate.ALGORITHMS`.
        partition: which joints and twist rows take part; None means ``Partition.auto(robot)``.
        dt: control period in seconds.
        singularity: what a step in the singular region does, a name of
            :data:`~pinrate.control.singularity.STRATEGIES` (see that module).
        wrist: how two aligned wrist axes share a rotation, a name of
            :data:`~pinrate.control.singularity.WRIST_STRATEGIES`; "split" (the contract's
            default, Barker eq. 61) leaves out the rotation the aligned axes cannot make,
            "turn" (servo's and the command line's default) turns the pair toward it.
        velocity_limits: None for the URDF's ``<limit velocity>`` of each joint (none where it
            gives 0 or none), a number for every joint, or one per velocity component (nv,),
            in rad/s or m/s; inf for none. When one binds, all rates are scaled alike.
        position_limits: keep q within the joints' position limits (see the module docstring).
        singular_threshold, slow_threshold: inverse condition numbers σ_min/σ_max of the
            inverted blocks (dimensionless, 0 <= singular < slow <= 1): under ``slow`` a step
            is in the singular region, under ``singular`` a block counts as singular.
        max_linear_speed, max_angular_speed: saturation of the commanded twist (m/s, rad/s;
            inf for none).
        elbow_region: rad; with ``singularity="auxiliary_elbow"``, Barker's elbow control acts
            while the elbow is closer than this to full extension (:mod:`.elbow`). None: the
            bend at which c of the measured block reaches ``slow_threshold`` at home (the
            elbow's whole singular region; 0.15 rad on the UR5), at most
            :data:`~pinrate.control.elbow.ELBOW_REGION`.
        posture: None (off), ``"home"`` or a configuration (nq,): a secondary task for
            redundant partitions moves the joints toward it and away from their limits in
            the null space of the twist (:mod:`.posture`), outside the singular region. Off
            by default, so the step's rates are the algorithm's.
        posture_gain: k (1/s) of the secondary task.
        acceleration_limits: None (the default: a URDF states none; MoveIt keeps them in
            ``joint_limits.yaml``), a number for every joint or one per velocity component
            (nv,), in rad/s² or m/s². With limits, the controller remembers the rates it
            applied last (:meth:`reset` forgets them) and moves each step's rates from those
            toward the new ones by at most a·dt per joint, one factor for all joints, so the
            change keeps its direction (``Status.RATE_LIMITED``). Position limits, the
            collision monitor and halts act at once, whatever the acceleration.
        collision: False (the default), True, or a
            :class:`~pinrate.control.collision.CollisionMonitor`: self-collision in the loop,
            from the URDF's collision geometry less the SRDF's disabled pairs. A step that
            brings two links closer is scaled down under the safety distance and halts before
            the stop distance; motion that separates them is always executed
            (``Status.DECELERATE_FOR_COLLISION``, ``Status.HALT_FOR_COLLISION``). A robot
            without collision geometry is not monitored (a warning says so, once).

    Raises:
        InputError: an unknown algorithm or strategy (the message lists the valid ones), a
            bad partition, a dt or speed that is not positive, thresholds out of order,
            velocity limits that are not positive or of the wrong length.
    """

    def __init__(
        self,
        robot: Robot,
        *,
        algorithm: str = "exact",
        partition: Partition | None = None,
        dt: float = 0.01,
        singularity: str = "decelerate",
        wrist: str = "split",
        velocity_limits: object = None,
        position_limits: bool = True,
        singular_threshold: float = SINGULAR_THRESHOLD,
        slow_threshold: float = SLOW_THRESHOLD,
        max_linear_speed: float = MAX_LINEAR_SPEED,
        max_angular_speed: float = MAX_ANGULAR_SPEED,
        elbow_region: float | None = None,
        posture: object = None,
        posture_gain: float = 1.0,
        acceleration_limits: object = None,
        collision: object = False,
    ) -> None:
        self.robot = robot
        self.algorithm = check_algorithm(algorithm)
        self.partition = partition_for(robot, partition)
        self.index = self.partition.resolve(robot)
        self.dt = check_positive(dt, "dt")
        self.singularity = check_strategy(singularity, STRATEGIES, "singularity strategy")
        self.wrist = check_strategy(wrist, WRIST_STRATEGIES, "wrist strategy")
        self.singular_threshold, self.slow_threshold = check_thresholds(singular_threshold, slow_threshold)
        self.max_linear_speed = check_positive(max_linear_speed, "max_linear_speed", allow_inf=True)
        self.max_angular_speed = check_positive(max_angular_speed, "max_angular_speed", allow_inf=True)
        if not isinstance(position_limits, bool):
            raise InputError(f"position_limits must be True or False, not {position_limits!r}")
        self.position_limits = position_limits
        facts = robot_facts(robot, self.partition)
        self.joint_limits = facts.limits
        """Every 1-DOF joint's position limits (:class:`~.robot_facts.Limit`)."""
        self.velocity_limits = (
            facts.urdf_velocity_limits.copy()
            if velocity_limits is None
            else per_joint(velocity_limits, "velocity_limits", robot)
        )
        self.acceleration_limits = (
            None if acceleration_limits is None else per_joint(acceleration_limits, "acceleration_limits", robot)
        )
        self.collision = monitor_for(robot, collision)
        """The self-collision monitor, or None."""
        self.characteristic_length = facts.characteristic_length
        """L (m): J's linear rows are divided by it before J is measured or pseudo-inverted."""
        index = self.index
        scale = row_scale(index.m, index.k, self.characteristic_length)
        ranks = facts.ranks
        names = self.partition.arm + self.partition.wrist  # partition order
        self.context = StepContext(
            robot=robot,
            partition=self.partition,
            index=index,
            names=names,
            positions={name: position for position, name in enumerate(names)},
            velocity_of=facts.velocity_of,
            algorithm=self.algorithm,
            measured=measured_blocks(self.algorithm),
            row_scale=scale,
            row_scale_column=scale[:, None],
            ranks={"J": ranks[0], "A": ranks[1], "W": ranks[2]},
            square_j=index.rows.size == index.columns.size == ranks[0],
            singular_threshold=self.singular_threshold,
            slow_threshold=self.slow_threshold,
            dt=self.dt,
            characteristic_length=self.characteristic_length,
        )
        """What the step's stages read (:class:`~.context.StepContext`)."""
        self.joggable: tuple[str, ...] = facts.joggable
        self.rule = RULES[self.singularity]
        """The singularity strategy's module (:class:`~.singularity.plan.Rule`)."""
        self._positions = PositionLimits(facts.limits, self.dt, position_limits)
        self.rate_limits = VelocityLimits(self.velocity_limits)
        """The velocity limits' stage (:class:`~.limits.velocity.VelocityLimits`)."""
        self._accelerations = (
            None
            if self.acceleration_limits is None
            else AccelerationLimits(self.acceleration_limits, self.dt, facts.velocity_of, self._positions)
        )
        self.posture_gain = check_positive(posture_gain, "posture_gain")
        self.posture = None if posture is None else PostureTask(self.context, posture, self.posture_gain)
        """The secondary task (:class:`~.posture.PostureTask`), or None."""
        self.elbow_region = 0.0 if elbow_region is None else check_positive(elbow_region, "elbow_region")
        self.auxiliary = (
            AuxiliaryElbow.find(self.context, self.wrist, None if elbow_region is None else self.elbow_region)
            if self.singularity == "auxiliary_elbow"
            else None
        )
        """Barker's auxiliary elbow control (:class:`~.singularity.auxiliary_elbow.AuxiliaryElbow`)
        when ``singularity="auxiliary_elbow"`` found an elbow, else None."""
        if self.auxiliary is not None:
            self.elbow_region = self.auxiliary.region
        self._solver = TwistSolver(self.context, self.auxiliary, self.posture, self.rate_limits)
        self._finish = Finish(
            robot, self.dt, self._positions, self.rate_limits, self._accelerations, self.collision, self.auxiliary
        )
        self._joint_space = JointSpace(self.context, facts, self._positions, self._finish)
        sight = Sight(self.algorithm, index, robot.nv, robot.sensor_id == robot.tip_id)
        self._core_step = CorePath(self.compiled, facts.limits, sight, self._wanted_twist, self.collision)
        self._built = True

    def __setattr__(self, name: str, value: object) -> None:
        # The stages copied the options when the controller was built: one changed afterwards
        # would act in some of them and not in others. Refused, with the way to do it.
        if name in option_names(Controller) and getattr(self, "_built", False):
            raise AttributeError(
                f"Controller.{name} is fixed when the controller is built: build a new Controller "
                "(Teleop.configure does so for a console)"
            )
        object.__setattr__(self, name, value)

    @property
    def elbow(self) -> Elbow | None:
        """The arm's elbow and shoulder when ``singularity="auxiliary_elbow"`` found one."""
        return None if self.auxiliary is None else self.auxiliary.elbow

    def compiled(self) -> CoreServo | None:
        """The compiled twin of this controller (:mod:`pinrate.compiled`); None where the Python
        path is chosen or the core does not cover it (:meth:`compiled_reason` says which)."""
        return None if self.compiled_reason() is not None else compiled_twin.twin(self)

    def compiled_reason(self) -> str | None:
        """Why this controller's loops run on Python though the core may be there (None when
        nothing in the configuration stops the core): the core's reason, or the first option
        :data:`~.compiled_twin.COMPILED_COVERAGE` does not cover at its value. An option
        missing from that table is not covered (fails closed)."""
        if type(self).step is not Controller.step:
            return f"{type(self).__name__} steps its own way: its loops run on the Python path"
        return compiled_twin.reason(self, option_names(type(self)))

    def check_inside_limits(self, q: np.ndarray) -> None:
        """InputError naming every joint ``q`` (nq,) puts outside its position limits, when the
        controller keeps them (:meth:`step` refuses such a q: it would have to snap the joint
        onto its limit, or leave it outside)."""
        self._positions.check_inside(q)

    def position_limit(self, number: int) -> Limit:
        """The ``number``-th position limit kept (the compiled core names a clamped joint by it)."""
        return self.joint_limits[number]

    def reset(self) -> None:
        """Forget what earlier steps left: the rates applied last (an acceleration-limited
        motion starts at rest) and the side of the elbow's last bend (the next bend from full
        extension goes the home's way)."""
        if self._accelerations is not None:
            self._accelerations.reset()
        if self.auxiliary is not None:
            self.auxiliary.reset()

    # ------------------------------------------------------------------ seeing
    def observe(self, q: object, goal: PoseGoal | None = None) -> Observation:
        """Kinematics and blocks at q (one Pinocchio pass); the pose error to ``goal`` too
        when given. q is checked (:meth:`Robot.check_q`)."""
        if goal is not None and not isinstance(goal, PoseGoal):
            raise InputError(f"goal must be a PoseGoal (PoseGoal.of(target, gain)), not {type(goal).__name__}")
        return self.observe_unchecked(self.robot.check_q(q), goal)

    def observe_unchecked(self, q: np.ndarray, goal: PoseGoal | None = None) -> Observation:
        """:meth:`observe` at a q that already went through :meth:`Robot.check_q` (or came out
        of a step): the servo's hot path."""
        jacobian, world_T_tip, world_T_sensor = self.robot.kinematics(q)
        error = None if goal is None else pose_error(world_T_tip, world_T_sensor, goal.target)[self.index.rows]
        return Observation(q, jacobian, world_T_tip, world_T_sensor, self.algorithm, self.index, goal, error)

    def conditioning(self, q: object) -> Conditioning:
        """The least inverse condition number σ_r/σ_1 of the blocks the algorithm inverts at q,
        which block, and its weakest joint motion (:mod:`pinrate.control.singularity`)."""
        return self.observed_conditioning(self.observe(q))

    def observed_conditioning(self, observation: Observation) -> Conditioning:
        """:meth:`conditioning` from an observation already made: no kinematics, so another
        thread (a display) may call it beside the control loop."""
        context = self.context
        return context.conditioning(context.reduced(observation.jacobian), self.index.arm_columns.size)

    # ------------------------------------------------------------------ acting
    def command_twist(self, observation: Observation, command: np.ndarray | PoseGoal) -> tuple[np.ndarray, bool]:
        """(twist, saturated): the command as a twist in partition order, sensor axes,
        saturated by one factor (:func:`~pinrate.kinematics.spatial.saturate_twist`)."""
        wanted = self._wanted_twist(observation, command)
        return saturate_twist(wanted, self.index.m, self.max_linear_speed, self.max_angular_speed)

    def _wanted_twist(self, observation: Observation, command: np.ndarray | PoseGoal) -> np.ndarray:
        """The command as a new twist array (m + k,; partition order, sensor axes), unsaturated."""
        if isinstance(command, PoseGoal):
            error = observation.error if observation.goal is command else None
            if error is None:
                error = pose_error(observation.world_T_tip, observation.world_T_sensor, command.target)[self.index.rows]
            return np.array(command.gain * error, dtype=float)
        return np.array(command, dtype=float)

    def step(self, q: object, command: object, *, observation: Observation | None = None) -> Step:
        """One control step from q: command -> twist -> joint rates -> next q.

        Args:
            q: the configuration (nq,); checked unless ``observation`` (taken at q) is given.
            command: a twist (m + k,) in partition order, sensor axes (m/s, rad/s), a
                :class:`PoseGoal`, a :class:`JointJog` or an :class:`Uncoupled` command
                (:mod:`pinrate.control.commands`).
            observation: :meth:`observe` at q, when the caller already has it (the servo
                measures its stop rules on it): it is reused, not recomputed.

        In the singular region the ``singularity=`` and ``wrist=`` strategies decide
        (:mod:`pinrate.control.singularity`); joints that the command would carry past a
        position limit are held at it while the others serve the command
        (``Status.JOINT_LIMIT``, ``frozen``); rates over a velocity limit are all scaled alike
        (``Status.RATE_LIMITED``). Never raises for what the robot does, and never returns
        NaN or inf.
        Where the core covers the controller, twist and pose steps run in it (:mod:`.core_step`).
        """
        taken = None if (core := self._core_step()) is None else core(q, command, observation)
        if taken:  # a Step; else None (the inputs go through Python's checks first) or False (Python's step)
            return taken
        if observation is None:
            observation = self.observe(q)
        self.check_inside_limits(observation.q)
        if isinstance(command, (JointJog, Uncoupled)):
            return self._joint_space.step(observation, command)
        if not isinstance(command, PoseGoal):
            command = check_vector(command, self.index.rows.size, "twist (linear then angular components)")
        if taken is None and core is not None and (taken := core(q, command, observation)):
            return taken  # inputs the core could not read (a list, say), now checked and converted
        twist, saturated = self.command_twist(observation, command)
        statuses = [Status.TWIST_SATURATED] if saturated else []
        details: list[str] = []
        unreachable = out_of_reach(self.context, observation, twist)
        if unreachable:
            statuses.append(Status.UNACHIEVABLE_TWIST)
            details.append(unreachable)
        bound = self.context.conditioning_bound(observation)
        auxiliary = self.auxiliary.plan(observation, twist) if self.auxiliary is not None else None
        plan = (
            plan_step(self.context, self.rule, self.wrist, observation, twist)
            if auxiliary is None and bound < self.slow_threshold
            else None
        )
        solve, frozen = self._solver(observation, twist, auxiliary, plan, statuses, details)
        try:
            rates = solve(frozenset())
            rates, frozen = self._positions.hold(observation, rates, solve, statuses, details, frozen)
        except SingularBlockError as singular:
            return self._finish.halt(observation, twist, str(singular))
        judged = (
            watched(self.context, observation, plan, bound, rates)
            if auxiliary is None and self.rule.decelerates
            else None
        )
        if judged is not None:
            scale, status, detail = decelerate(self.context, observation, rates, *judged)
            if status is Status.HALT_FOR_SINGULARITY:
                return self._finish.halt(observation, twist, detail)
            if status is not Status.OK:
                rates = rates * scale
                statuses.append(status)
                details.append(detail)  # NEAR_SINGULARITY: a way out, scale 1
        return self._finish(observation, twist, rates, statuses, details, frozen)


COMPILED_COVERAGE = compiled_twin.COMPILED_COVERAGE

CONTROLLER_OPTIONS = tuple(name for name in option_names(Controller) if name != "robot")
"""Every keyword option of :class:`Controller` (what :func:`~.servo_loop.servo` passes on)."""


__all__ = [
    "COMPILED_COVERAGE",
    "CONTROLLER_OPTIONS",
    "MAX_ANGULAR_SPEED",
    "MAX_LINEAR_SPEED",
    "Controller",
    "Observation",
    "PoseGoal",
    "Step",
    "error_norms",
]
