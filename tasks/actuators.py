"""What a robot file's actuators do, read once for every part that drives them: the
realisations on a file's own actuators (tasks.realisations: wheel_motors, joint_motors,
gait) and the mount kinds that check a file before it is loaded (tasks.mount.kinds).

- `kind`: an actuator's kind by its gain, bias and activation dynamics (not by its
  element's name): a torque motor, a position servo or a velocity servo (ACTUATOR_KINDS), or None
  (`why_other`: the term, gain, bias or dyn, that makes it none of them). `model_kind`
  reads a compiled model's actuator, `spec_kind` an MjSpec's (and `model_why_other`,
  `spec_why_other`).
- `joints_moved`: the joints an MjSpec's actuator acts on, directly or by a fixed tendon.
- `motor_forces`, `length_gains`, `control_ranges`: a compiled model's actuators measured
  at its rest pose (their generalised force per unit control; their length per unit of
  a joint), and their control ranges.
- `require_independent`: the refusal of motors that cannot move two joints apart.

Nothing heavy is imported at the top: the mount parser uses this module before MuJoCo is
needed, and the kernels read ACTUATOR_KINDS.
"""
import numpy as np
from models import ContractError

#: The actuators' kinds a controller knows, as the docs and errors write them (their
#: index is the joint_motors controller's code: tasks.kernels.joint_motors).
ACTUATOR_KINDS = ("torque motors", "position servos", "velocity servos")
#: The control each motor is probed with at load, to measure its generalised force per
#: unit control (small, so no joint's actuatorfrcrange clips it).
PROBE = 1e-3


def kind(gaintype, gainprm, biastype, biasprm, dyntype):
    """An actuator's kind (ACTUATOR_KINDS) from its parameters, None for another (`why_other`
    says which term makes it so):
    - a torque motor (MuJoCo's <motor>, or a <general> whose affine bias is all zeros):
      a fixed gain, no bias, no activation dynamics;
    - a position servo (<position>, or a <general> of bias -kp * length, any damping):
      its control is the length it holds;
    - a velocity servo (<velocity>: bias -kv * speed, no position term, no activation
      dynamics): its control is the speed it holds."""
    return _classify(gaintype, gainprm, biastype, biasprm, dyntype)[0]


def why_other(gaintype, gainprm, biastype, biasprm, dyntype):
    """For an actuator of no kind (kind is None), the term that makes it so (gain, bias
    or dyn) and its value, in a few words; None for one of ACTUATOR_KINDS."""
    return _classify(gaintype, gainprm, biastype, biasprm, dyntype)[1]


def _classify(gaintype, gainprm, biastype, biasprm, dyntype):
    """(kind, None) or (None, the reason) of kind and why_other."""
    import mujoco
    if int(gaintype) != int(mujoco.mjtGain.mjGAIN_FIXED):
        return None, f"gain: gaintype {mujoco.mjtGain(int(gaintype)).name[7:].lower()} (not fixed)"
    none = int(dyntype) == int(mujoco.mjtDyn.mjDYN_NONE)
    dyn = f"dyn: dyntype {mujoco.mjtDyn(int(dyntype)).name[6:].lower()}"
    gain = gainprm[0]
    if int(biastype) == int(mujoco.mjtBias.mjBIAS_NONE) or (
            int(biastype) == int(mujoco.mjtBias.mjBIAS_AFFINE)
            and biasprm[0] == biasprm[1] == biasprm[2] == 0.0):
        if gain == 0.0:
            return None, "gain: 0 (its control moves nothing)"
        return (ACTUATOR_KINDS[0], None) if none else (None, f"{dyn} (a torque motor's force would "
                                                    "lag its control)")
    if int(biastype) != int(mujoco.mjtBias.mjBIAS_AFFINE):
        return None, f"bias: biastype {mujoco.mjtBias(int(biastype)).name[7:].lower()}"
    if biasprm[0] != 0.0:
        return None, f"bias: a constant term (biasprm[0] = {biasprm[0]:g})"
    if biasprm[1] == -gain != 0.0:
        return ACTUATOR_KINDS[1], None
    if biasprm[1] != 0.0:
        return None, (f"bias: its length term (biasprm[1] = {biasprm[1]:g}) is not -gain "
                      f"({-gain:g}), so its control is no length it holds")
    if biasprm[2] != -gain or gain == 0.0:
        return None, (f"bias: its speed term (biasprm[2] = {biasprm[2]:g}) is not -gain "
                      f"({-gain:g}), so its control is no speed it holds")
    return (ACTUATOR_KINDS[2], None) if none else (None, f"{dyn} (a velocity servo's force would "
                                                "lag its control)")


def model_kind(model, a):
    """The kind of a compiled model's actuator a (an MjModel)."""
    return kind(model.actuator_gaintype[a], model.actuator_gainprm[a], model.actuator_biastype[a],
                model.actuator_biasprm[a], model.actuator_dyntype[a])


def spec_kind(act):
    """The kind of an MjSpec's actuator."""
    return kind(act.gaintype, act.gainprm, act.biastype, act.biasprm, act.dyntype)


def model_why_other(model, a):
    """why_other of a compiled model's actuator a (an MjModel)."""
    return why_other(model.actuator_gaintype[a], model.actuator_gainprm[a],
                     model.actuator_biastype[a], model.actuator_biasprm[a],
                     model.actuator_dyntype[a])


def spec_why_other(act):
    """why_other of an MjSpec's actuator."""
    return why_other(act.gaintype, act.gainprm, act.biastype, act.biasprm, act.dyntype)


#: What to do about an actuator of no kind (the refusals' advice).
OTHER_ADVICE = ("drive those joints through actuators that act as torque motors, position "
                "servos or velocity servos, or through another action kind")


def joints_moved(spec, act):
    """The names of the joints an MjSpec's actuator acts on: its joint, or the joints a
    fixed tendon it pulls wraps; empty for any other transmission."""
    import mujoco
    if act.trntype == mujoco.mjtTrn.mjTRN_JOINT:
        return {act.target}
    if act.trntype == mujoco.mjtTrn.mjTRN_TENDON:
        tendon = next((t for t in spec.tendons if t.name == act.target), None)
        if tendon is not None:
            return {w.target.name for w in tendon.path if w.type == mujoco.mjtWrap.mjWRAP_JOINT}
    return set()


def motor_forces(model, motors, dofs, rest=None):
    """forces[k, j]: motor k's generalised force on dof j per unit of its control, measured
    on a scratch MjData at the model's rest pose (rest: a qpos; default qpos0;
    qfrc_actuator with motor k's control at PROBE and the others 0, less with all 0,
    over PROBE; control clamping off meanwhile)."""
    import mujoco
    d = mujoco.MjData(model)
    if rest is not None:
        d.qpos[:] = rest
    flags = model.opt.disableflags
    model.opt.disableflags = flags | int(mujoco.mjtDisableBit.mjDSBL_CLAMPCTRL)
    try:
        mujoco.mj_forward(model, d)
        rest = d.qfrc_actuator[dofs].copy()
        forces = np.zeros((len(motors), len(dofs)))
        for k, a in enumerate(motors):
            d.ctrl[:] = 0.0
            d.ctrl[a] = PROBE
            mujoco.mj_forward(model, d)
            forces[k] = (d.qfrc_actuator[dofs] - rest) / PROBE
    finally:
        model.opt.disableflags = flags
    return forces


def length_gains(model, qadrs, rest=None):
    """(gain, lengths): gain[a, j] every actuator's length per unit of the joint at qpos
    address qadrs[j] (central differences at the rest pose, rest: a qpos, default
    qpos0; entries under 1e-9 zeroed), and the actuators' lengths at rest. For a joint or
    a fixed tendon this is the transmission's gear times coefficient, whatever the
    actuator's kind."""
    import mujoco
    rest = model.qpos0 if rest is None else rest
    d = mujoco.MjData(model)
    gain = np.zeros((model.nu, len(qadrs)))
    h = 1e-3
    for c, q in enumerate(qadrs):
        lengths = []
        for delta in (h, -h):
            d.qpos[:] = rest
            d.qpos[q] += delta
            mujoco.mj_fwdPosition(model, d)
            lengths.append(d.actuator_length.copy())
        gain[:, c] = (lengths[0] - lengths[1]) / (2 * h)
    gain[np.abs(gain) < 1e-9] = 0.0
    d.qpos[:] = rest
    mujoco.mj_fwdPosition(model, d)
    return gain, d.actuator_length.copy()


def control_ranges(model, actuators):
    """(lo, hi): the actuators' control ranges, infinite where unlimited."""
    lo = model.actuator_ctrlrange[actuators, 0].copy()
    hi = model.actuator_ctrlrange[actuators, 1].copy()
    unlimited = ~model.actuator_ctrllimited[actuators].astype(bool)
    lo[unlimited], hi[unlimited] = -np.inf, np.inf
    return lo, hi


def require_independent(forces, mtm, field):
    """models.ContractError naming the mount's `field` when the motors, of forces `forces` on two joints
    and Gram matrix mtm (a, b, e, det: tasks.kernels.plan.gram), cannot move the two
    joints apart: the determinant 0, to rounding."""
    a, _, e, det = mtm
    if abs(det) <= 1e-12 * max(1e-300, a + e) ** 2:
        raise ContractError("the motors do not move the two joints independently (force per "
                            f"unit control on them: {forces.tolist()})", field=field)
