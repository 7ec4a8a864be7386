"""The arm's tunables and the gripper's dimensions, named and documented in one place (SI units).

One frozen :class:`ArmConfig`; :data:`ARM` is the robot's instance, read by the controller (:mod:`.arm_controller`,
:mod:`.arm_grasp`), the body (:mod:`.arm_body`), the planner's macros (:mod:`.arm_macros`) and the task families
that size scenes to the gripper. The workspace
and the opening come from the task (:class:`~robotool.robots.arm.arm_skills.ArmLimits`); the servos' and the
contacts' physics from :mod:`.arm_body`.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class ArmConfig:
    """The arm's tunables (one instance per robot: :data:`ARM`)."""

    home: tuple[float, float, float] = (0.1, 0.0, 0.3)
    """m: the gripper centre at the start."""
    speed: float = 0.25
    """m/s: the straight-line reference speed of a move."""
    reached: float = 0.005
    """m: a move is done when the centre is this close to the target."""
    stall_error: float = 0.01
    """m: the centre this far behind the reference, ..."""
    stall_speed: float = 0.02
    """m/s: ... moving slower than this, ..."""
    stall_time: float = 0.3
    """s: ... for this long is a stall."""
    max_lead: float = 0.06
    """m: the reference a move writes stays this close to the gripper centre on each axis, and follows the
    straight-line reference at ``speed`` at most (anti-windup): a blocked servo cannot build up a pull that flings the
    gripper when the obstruction gives way. At ``speed`` the servos track about 0.05 m behind the reference (a tick of
    look-ahead, their filter and their damping) and reach their force limit 0.05 m from it, so unblocked motions and
    full pushes are as before; a released gripper lurches this far at most, then moves at ``speed``."""
    time_margin: float = 2.0
    """s a move may take beyond distance / speed."""
    gripper_time: float = 0.3
    """s to open or close the fingers."""
    finger_half: tuple[float, float, float] = (0.008, 0.004, 0.023)
    """m: half sizes of a finger (x, y across the closing axis, z)."""
    finger_z: float = 0.007
    """m: a finger's centre above the gripper centre (the tips reach 0.016 m below it)."""
    palm_half: tuple[float, float, float] = (0.02, 0.05, 0.01)
    """m: half sizes of the palm."""
    palm_clearance: float = 0.03
    """m from the gripper centre up to the palm's underside."""
    grip_tolerance: float = 0.003
    """m: geometry within this of a finger counts as next to it."""
    on_top: float = 0.002
    """m: fingertips less than this below an object's top rest on it."""
    opening_give: float = 1e-4
    """m the open fingers' stops may give before what is between them counts as too wide."""
    side_slack: float = 0.001
    """m: beside the fingers, an object they grip may reach this far into them (contact give)."""
    clamp_tolerance: float = 1e-4
    """m: a target this close to the workspace counts as inside (no clamp is reported)."""
    on_sheet: float = 0.003
    """m: a fingertip this close above a top face (or a sheet) it overlaps rests on it."""
    pushed_out: float = 0.02
    """m an object must be pushed further out of the workspace to be reported."""
    grip_force: float = 60.0
    """N each pad squeezes with: the continuous squeeze of a parallel gripper of this size (a Franka hand's is 70 N);
    the largest load an honest tool puts on it, the hammer held by its handle end with its head 0.17 m away, needs
    0.71 N m across the pads' 16 mm, 45 N."""
    grip_friction: float = 1.0
    """The pads hold by friction this many times the squeeze."""
    slip_margin: float = 1.5
    """How many times the static rule's couples (``grip_force`` across the grip's depth and width) the pads hold
    against a twist or tilt while an object is held: the static rule is kept on the safe side, and a pad's torsional
    friction over its whole patch holds about half as much again (about 1.5 N m for 16 mm pads). The hammer held by its
    handle end pulling a carton in loads its grip to 1.25 times the static couple; raking in a load several times its
    own weight goes past this. The force is held up to the pads' friction, ``2 grip_friction grip_force``, exactly."""
    slip_time: float = 0.3
    """s: a grip loaded past what it holds for this long in all while it holds (three 0.1 s ticks) slips and lets go
    (slip adds up: a load that keeps coming back in short bursts slips it as a steady one does). The planner's tool
    pulls go past it for one tick at most (a tool's head landing on the table), a stick tipping a carton over
    by its top edge for two."""
    payload_time: float = 0.3
    """s: an arm that has carried more than ``max_payload`` for this long in all over the run (three 0.1 s ticks)
    carried too much (:mod:`.arm_payload`): an instant's peak, a load coming off its support or a pushed crate
    hopping against a held tool for a tick, is ridden out, as a real arm's peak torque rides it out; a lift of any
    use lasts longer. The time adds up across grasps, so a load cannot be carried in hops with regrasps between."""
    contact_lift: float = 1.0
    """N: the least net upward force the robot's bodies put through their contacts on a group of objects it does not
    grasp for the group to count as held up by them (:mod:`.arm_payload`); less is a push, a drag or a graze."""
    press_travel: float = 0.005
    """m: a push, a drag or a press that takes more of the arm than ``max_payload`` holds up counts only once the
    pushes over it have moved what they push this far up or sideways (any point of it: a beam turned about its middle
    moves its ends), and worked the gripper along them as much as a push at the limit does over this far (a push of
    twice the limit: half as far), in all over the run (:mod:`.arm_payload`): a press into a support (a block set down
    with its target below the support, the stack under it sinking a few millimetres into its soft contacts; the
    fingers driven into the table) is no load; a lever's end pressed down under a heavy load raises the load
    centimetres (a steep lever while its end sinks 3 mm, found by an adversarial run), and a heavy crate pushed along
    in strokes of a few millimetres goes this far in two."""
    edge_share: float = 0.5
    """The least share of what the pads could cover of an object across their width that is a grip rather than a
    pinch at its edge."""
    slab_cylinder_sides: int = 32
    """A cylinder counts as the prism of this many sides around it (0.5% wider at most) when finding what lies
    between the fingers."""

    # the planner's macros (:mod:`.arm_macros`)
    approach_height: float = 0.08
    """m above a grasp point to approach from."""
    slide_lift: float = 0.004
    """m a held object is lifted off the table while it pushes things."""
    tool_gap: float = 0.03
    """m between a tool's face and an object before a push or pull."""
    inside_margin: float = 0.06
    """m inside the workspace where objects are brought."""
    carry_clearance: float = 0.03
    """m a carried object clears everything below it."""
    press_depth: float = 0.03
    """m a face is pushed in past where it starts."""
    stow_back: float = 0.1
    """m a tool is set down behind where it pushed from."""
    attach_depth: float = 0.008
    """m a magnetic chain is pushed into the next object to touch it: with slack for a chain held a few mm back as it
    stalls against the object (at 4 mm, the chain's end stopped 0.1 mm short of the third cube in a perturbed world the
    planner had not seen, and the button was pressed with two cubes, short of it)."""


ARM = ArmConfig()
"""The arm's tunables."""


def finger_open(gripper_opening: float) -> float:
    """Each finger's offset from the gripper centre when open (0 when fully closed), m, for the task's opening."""
    return gripper_opening / 2 + ARM.finger_half[1]
