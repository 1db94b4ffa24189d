# SPDX-License-Identifier: Apache-2.0
"""A fast stand-in for the twin's motor current, for the iterations of urt_identify.py only
(the numbers it reports come from the twin's own replay):

  i_j = [ (τ_rb,j + T_f,j(q̇_j) + J_CS q̈_j) / r_s + (J_M + J_WG) r q̈_j ] / k_t + i_off,j

τ_rb: the rigid arm's inverse dynamics at the set-point (Pinocchio, built from the parameters
urtwin resolved, the frames of tests/python/test_arm_pinocchio.py), linear in the links'
inertial parameters π, so its regressor is computed once per recording. r = Z_CS/(Z_CS − Z_FS)
and r_s = r / cos² α_n the gear's kinematic and static ratios (model.md §1.5). T_f is the LuGre
law in steady sliding, sgn(q̇)·g(q̇) with the sign smoothed over a few mrad/s (the bristles carry
the torque through rest), g as in drivers/include/urt/drivers/friction.h with the asymmetry."""

import numpy as np
import pinocchio as pin

NJ = 6
SIGN_EPS = 2e-3  # [rad/s] width of the smoothed sign of q̇


def _rot(axis, t):
    c, s = np.cos(t), np.sin(t)
    if axis == "x":
        return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
    if axis == "y":
        return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _tail(link):
    return pin.SE3(_rot("x", link["alpha"]) @ _rot("y", link["beta"]),
                   np.array([link["a"], 0.0, 0.0]))


def _body(mass, com, inertia):
    ixx, iyy, izz, ixy, ixz, iyz = inertia
    ic = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    return pin.Inertia(mass, np.asarray(com, dtype=float), ic)


class Arm:
    """The rigid arm of the resolved model; dynamic parameters π per link in joint frames."""

    def __init__(self, params):
        arm = params["arm"]
        self.links = arm["links"]
        self.model = pin.Model()
        self.model.gravity = pin.Motion(np.array(arm["gravity"], dtype=float), np.zeros(3))
        parent, tail = 0, pin.SE3.Identity()
        self.tails = []
        for i, link in enumerate(self.links):
            head = pin.SE3(_rot("z", link["theta"]), np.array([0.0, 0.0, link["d"]]))
            jid = self.model.addJoint(parent, pin.JointModelRZ(), tail * head, f"joint{i + 1}")
            tail = _tail(link)
            self.tails.append(tail)
            self.model.appendBodyToJoint(
                jid, tail.act(_body(link["mass"], link["com"], link["inertia"])),
                pin.SE3.Identity())
            parent = jid
        self.data = self.model.createData()
        self.flange = tail  # joint-6 frame → flange (DH frame 6)

    def pi(self, mass, com, payload=None):
        """π (60) for link masses [6] and CoMs [6][3] in DH frames; payload = (m, cog) on the
        flange (cog in the flange frame, a point mass) or None."""
        out = []
        for i, link in enumerate(self.links):
            body = self.tails[i].act(_body(mass[i], com[i], link["inertia"]))
            if i == NJ - 1 and payload is not None and payload[0] > 0.0:
                body = body + self.flange.act(pin.Inertia(payload[0], np.asarray(payload[1]),
                                                          np.zeros((3, 3))))
            out.append(body.toDynamicParameters())
        return np.concatenate(out)

    def regressor(self, q, qd, qdd):
        """(n, 6, 60) joint-torque regressor along a recording."""
        n = q.shape[0]
        y = np.empty((n, NJ, 10 * NJ))
        for k in range(n):
            y[k] = pin.computeJointTorqueRegressor(self.model, self.data, q[k], qd[k], qdd[k])
        return y


class Drives:
    """The per-joint constants of the current law, from the resolved model."""

    def __init__(self, params):
        js = params["joints"]
        self.kt = np.array([j["motor"]["kt"] for j in js])
        self.jm = np.array([j["motor"]["j"] for j in js])
        self.ratio = np.array([j["gear"]["ratio"] for j in js])
        self.r_static = self.ratio / np.cos(np.array([j["gear"]["alpha_n"] for j in js])) ** 2
        self.jwg = np.array([j["gear"]["j_wg"] for j in js])
        self.jcs = np.array([j["gear"]["j_cs"] for j in js])
        self.k_q = np.array([j["friction"]["k_q"] for j in js])
        self.i_max = np.array([j["control"]["i_max"] for j in js])


def friction_torque(qd, f_c, f_v, k_static, qd_s, asym, k_q):
    """Steady-sliding LuGre torque sgn(q̇)·g(q̇) with a smoothed sign; (n, 6)."""
    v = np.abs(qd)
    fc = f_c * (1.0 + asym * np.sign(qd))
    g = fc * (1.0 + k_static * np.exp(-k_q * v / qd_s)) + f_v * np.cbrt(v * v)
    return np.tanh(qd / SIGN_EPS) * g


def current(drives, tau_rb, qd, qdd, fr, i_off, kt=None):
    """Motor current [A] (n, 6) for rigid-body torque tau_rb and friction parameters fr (a dict
    of per-joint arrays f_c, f_v, k_static, qd_s, asym); kt the motor torque constants
    (default: the model's)."""
    kt = drives.kt if kt is None else kt
    t_f = friction_torque(qd, fr["f_c"], fr["f_v"], fr["k_static"], fr["qd_s"], fr["asym"],
                          drives.k_q)
    t_out = tau_rb + t_f + drives.jcs * qdd
    return (t_out / drives.r_static + (drives.jm + drives.jwg) * drives.ratio * qdd) / kt \
        + i_off
