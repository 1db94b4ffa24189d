# SPDX-License-Identifier: Apache-2.0
"""Cross-check of the rigid-arm code (core/arm.cpp) against Pinocchio.

The Pinocchio model is built from the parameters urtwin itself resolved (urt_config --print
--json), with eq. (8) of the paper written out independently here: joint i is a revolute-Z
joint placed at F_{i−1}·Transl(z, d_i)·Rot(z, θ_i) in joint i−1's frame, where
F = Transl(x, a)·Rot(x, α)·Rot(y, β) is the constant tail of the previous link's transform;
link i's inertia (given in DH frame i about its CoM, model.md §1.8) is carried into joint i's
frame by F_i. Every quantity must agree to 1e-9 relative on 1000 random states, for the bare
flange of config/ur5.yaml, again with a tool (TCP offset and rotation) set by an override, and
with a payload (config `payload:`) appended to link 6 as a second Pinocchio body of joint 6.
"""

import types

import numpy as np
import pinocchio as pin
import pytest

import urtwin_ctypes as urt

N_STATES = 1000
RTOL = 1e-9
SEED = 20230711


def rot_x(t):
    c, s = np.cos(t), np.sin(t)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(t):
    c, s = np.cos(t), np.sin(t)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(t):
    c, s = np.cos(t), np.sin(t)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def link_tail(link):
    """F = Transl(x, a)·Rot(x, α)·Rot(y, β): the part of eq. (8) after the joint rotation."""
    return pin.SE3(rot_x(link["alpha"]) @ rot_y(link["beta"]), np.array([link["a"], 0.0, 0.0]))


def build_pinocchio(params):
    """Pinocchio model of the arm, and the id of its TCP frame."""
    arm = params["arm"]
    model = pin.Model()
    model.gravity = pin.Motion(np.array(arm["gravity"], dtype=float), np.zeros(3))
    parent, tail = 0, pin.SE3.Identity()
    for i, link in enumerate(arm["links"]):
        # the θ offset is folded into the placement, so Pinocchio's q is the paper's q
        head = pin.SE3(rot_z(link["theta"]), np.array([0.0, 0.0, link["d"]]))
        joint = model.addJoint(parent, pin.JointModelRZ(), tail * head, f"joint{i + 1}")
        ixx, iyy, izz, ixy, ixz, iyz = link["inertia"]
        inertia_c = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
        body = pin.Inertia(link["mass"], np.array(link["com"], dtype=float), inertia_c)
        tail = link_tail(link)
        model.appendBodyToJoint(joint, tail.act(body), pin.SE3.Identity())
        parent = joint
    # the payload: CoG in the flange frame (DH frame 6, as link 6's CoM), inertia about the CoG
    load = params["payload"]
    ixx, iyy, izz, ixy, ixz, iyz = load["inertia"]
    inertia_c = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    model.appendBodyToJoint(parent, tail.act(pin.Inertia(float(load["mass"]),
                                                         np.array(load["cog"], dtype=float),
                                                         inertia_c)), pin.SE3.Identity())
    tcp = np.array(arm["tcp"], dtype=float)
    tcp_frame = model.addFrame(
        pin.Frame("tcp", parent, tail * pin.SE3(pin.exp3(tcp[3:]), tcp[:3]),
                  pin.FrameType.OP_FRAME))
    return model, tcp_frame


# the bare flange of config/ur5.yaml, and a tool 15 cm out, turned by 2.35 rad
TOOL = [0.01, -0.02, 0.15, 0.3, -1.2, 2.0]
# and a 3 kg payload off the flange axis with a full inertia tensor (a 0.1 × 0.06 × 0.04 m
# block, turned so that the products of inertia are not zero)
PAYLOAD = ("payload.mass=3.0", "payload.cog=[0.02, -0.015, 0.1]",
           "payload.inertia=[0.0013, 0.0029, 0.0034, 0.0004, -0.0002, 0.0003]")
VARIANTS = {"bare_flange": ((), [0.0] * 6),
            "tool": ((f"arm.tcp=[{', '.join(map(repr, TOOL))}]",), TOOL),
            "payload": (PAYLOAD, [0.0] * 6)}


@pytest.fixture(scope="module", params=list(VARIANTS))
def arm(request, urtwin_lib, ur5_params):
    """urtwin's model and the Pinocchio model built from the same resolved parameters."""
    overrides, tcp = VARIANTS[request.param]
    params = urt.resolved_model(urt.UR5_YAML, overrides) if overrides else ur5_params
    assert params["arm"]["tcp"] == pytest.approx(tcp, abs=1e-15)
    assert params["payload"]["mass"] == (3.0 if request.param == "payload" else 0.0)
    model, tcp_frame = build_pinocchio(params)
    with urt.Model(urtwin_lib, urt.UR5_YAML, overrides) as ours:
        yield types.SimpleNamespace(urt=ours, params=params, model=model,
                                    data=model.createData(), tcp=tcp_frame)


@pytest.fixture(scope="module")
def states():
    """Random (q, qd, qdd, tau) within and somewhat beyond the UR5's working envelope."""
    rng = np.random.default_rng(SEED)
    tau_max = np.array([150.0, 150.0, 150.0, 28.0, 28.0, 28.0])
    return [(rng.uniform(-np.pi, np.pi, 6), rng.uniform(-3.2, 3.2, 6),
             rng.uniform(-15.0, 15.0, 6), rng.uniform(-1.0, 1.0, 6) * tau_max)
            for _ in range(N_STATES)]


def rel_err(got, want):
    """Norm-wise relative error ‖got − want‖∞ / ‖want‖∞."""
    got, want = np.asarray(got), np.asarray(want)
    return np.max(np.abs(got - want)) / max(np.max(np.abs(want)), 1e-300)


def check(name, errors):
    worst = max(errors)
    print(f"\n{name}: max relative error {worst:.2e} over {len(errors)} values")
    assert worst < RTOL, f"{name}: max relative error {worst:.3e} >= {RTOL}"


def test_mass_matrix_matches_pinocchio_crba(arm, states):
    model, data, ur5 = arm.model, arm.data, arm.urt
    errors, scaled = [], []
    for q, _, _, _ in states:
        want = pin.crba(model, data, q)
        want = np.triu(want) + np.triu(want, 1).T  # Pinocchio fills the upper triangle
        got = ur5.mass_matrix(q)
        errors.append(rel_err(got, want))

        # entry-wise on the diagonally scaled matrix, so the tiny wrist-3 entries count too
        d = np.sqrt(np.diag(want))
        scaled.append(np.max(np.abs(got - want) / np.outer(d, d)))
    check("mass matrix", errors)
    check("mass matrix, diagonally scaled", scaled)


def test_rnea_matches_pinocchio_rnea(arm, states):
    model, data, ur5 = arm.model, arm.data, arm.urt
    errors = [rel_err(ur5.rnea(q, qd, qdd), pin.rnea(model, data, q, qd, qdd))
              for q, qd, qdd, _ in states]
    check("rnea", errors)


def test_gravity_matches_pinocchio_generalized_gravity(arm, states):
    model, data, ur5 = arm.model, arm.data, arm.urt
    errors = [rel_err(ur5.gravity(q), pin.computeGeneralizedGravity(model, data, q))
              for q, _, _, _ in states]
    check("gravity", errors)


def test_forward_dynamics_matches_pinocchio_aba(arm, states):
    model, data, ur5 = arm.model, arm.data, arm.urt
    errors = [rel_err(ur5.forward_dynamics(q, qd, tau), pin.aba(model, data, q, qd, tau))
              for q, qd, _, tau in states]
    check("forward dynamics (ABA)", errors)


def test_tcp_pose_matches_pinocchio_frame_placement(arm, states):
    model, data, ur5 = arm.model, arm.data, arm.urt
    pos, rot = [], []
    for q, _, _, _ in states:
        pin.framesForwardKinematics(model, data, q)
        want = data.oMf[arm.tcp]
        pose = ur5.tcp_pose(q)
        pos.append(rel_err(pose[:3], want.translation))

        # compare rotations as matrices (a rotation vector near π may flip sign legitimately)
        # and insist on the UR range of the angle, [0, π]; compare the vectors themselves only
        # below 3 rad, since Pinocchio's log3 loses digits near π (3e-12 at 3.13 rad, where
        # ours still maps back to the matrix within 1e-15)
        assert np.linalg.norm(pose[3:]) <= np.pi
        rot.append(np.max(np.abs(pin.exp3(pose[3:]) - want.rotation)))
        if np.linalg.norm(pin.log3(want.rotation)) < 3.0:
            rot.append(rel_err(pose[3:], pin.log3(want.rotation)))
    check("TCP position", pos)
    check("TCP rotation", rot)


def test_frames_match_pinocchio_joint_placements(arm, states):
    model, data, ur5 = arm.model, arm.data, arm.urt
    tails = [link_tail(link) for link in arm.params["arm"]["links"]]
    errors = []
    for q, _, _, _ in states[:200]:
        pin.forwardKinematics(model, data, q)
        for i in range(1, 7):
            # DH frame i is joint i's frame followed by link i's constant tail
            want = (data.oMi[i] * tails[i - 1]).homogeneous
            errors.append(rel_err(ur5.frame(q, i), want))
    check("DH frames", errors)


def test_jacobian_matches_pinocchio_frame_jacobian(arm, states):
    model, data, ur5 = arm.model, arm.data, arm.urt
    errors = []
    for q, _, _, _ in states:
        # rows (v; ω) of the TCP point in base-frame axes = LOCAL_WORLD_ALIGNED
        want = pin.computeFrameJacobian(model, data, q, arm.tcp, pin.LOCAL_WORLD_ALIGNED)
        errors.append(rel_err(ur5.jacobian(q), want))
    check("Jacobian", errors)


def test_energy_matches_pinocchio_kinetic_plus_potential(arm, states):
    model, data, ur5 = arm.model, arm.data, arm.urt
    errors = []
    for q, qd, _, _ in states:
        want = (pin.computeKineticEnergy(model, data, q, qd) +
                pin.computePotentialEnergy(model, data, q))
        errors.append(abs(ur5.energy(q, qd) - want) / max(abs(want), 1.0))
    check("energy", errors)
