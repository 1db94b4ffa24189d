# SPDX-License-Identifier: Apache-2.0
"""urtwin from Python: the UR5 digital twin's physics core, offline.

    import urtwin
    m = urtwin.Model(overrides={"sensors.noise": False})        # config/ur5.yaml by default
    r = urtwin.run(m, "excitation", traj_seed=3, duration=2.0, decimate=40)
    r["i_meas"]          # (n, 6) measured motor current [A]; r.t the times [s]
    r.csv_columns()      # the columns of `urt_sim --out`, same names and the same bits

A run plays its set-point through urt_step exactly as tools/urt_sim.cpp does (the loop is C++,
python/src/run.cpp, and releases the GIL while it steps, so threads run in parallel). Bad
input (wrong shapes, NaN, unknown config keys) raises ValueError with the C core's message;
a run that fails at run time (a refused command, a failed step) raises RuntimeError.
"""

import os
from pathlib import Path

import numpy as np

from . import _urtwin

__version__ = "0.1.0"
__all__ = ["Model", "Trajectory", "Result", "run", "excitation", "pickplace", "hold",
           "from_arrays", "from_record_csv", "read_record_csv", "default_config",
           "CHANNELS", "FAULTS_AVAILABLE", "FAULT_CLASSES"]

NJ = _urtwin.NJ
Trajectory = _urtwin.Trajectory

# liburtwin has fault injection (core/include/urt/faults.h): run(..., faults=...) and the
# dataset's faults axis
FAULTS_AVAILABLE = True

# the fault classes as scenario files spell them, in the order of the truth channels
FAULT_CLASSES = list(_urtwin.fault_classes())


def _fault_keys(x):
    """PyYAML reads the YAML 1.1 booleans on/off as True/False, keys too: an intermittent
    profile's `on:` and `off:` come back as True and False. Give them their names back (the
    C loader reads the text, where they are plain keys)."""
    if isinstance(x, dict):
        return {({True: "on", False: "off"}[k] if isinstance(k, bool) else k): _fault_keys(v)
                for k, v in x.items()}
    if isinstance(x, list):
        return [_fault_keys(v) for v in x]
    return x


def _fault_args(faults):
    """(file, yaml_text, name) for _urtwin.run from run()'s faults argument."""
    if faults is None:
        return None, None, "faults"
    if isinstance(faults, os.PathLike):
        return os.fspath(faults), None, "faults"
    if isinstance(faults, str):
        # YAML text has a newline or starts with the document's key; anything else is a path
        if "\n" in faults or faults.lstrip().startswith("faults:"):
            return None, faults, "<faults>"
        return faults, None, "faults"
    if isinstance(faults, (list, tuple)):
        faults = {"faults": list(faults)}
    if isinstance(faults, dict):
        faults = _fault_keys(faults)
        import yaml
        # dumped one key a line, so the parser's line numbers point into this text
        return None, yaml.safe_dump(faults, sort_keys=False, default_flow_style=False), \
            "<faults>"
    raise TypeError("faults: expected a scenario file path, YAML text, a dict {faults: [...]} "
                    "or a list of fault specs")


def default_config():
    """config/ur5.yaml: the checkout's, or the copy installed into the wheel."""
    here = Path(__file__).resolve().parent
    for p in (here / "config" / "ur5.yaml", here.parents[1] / "config" / "ur5.yaml"):
        if p.is_file():
            return str(p)
    raise FileNotFoundError("config/ur5.yaml not found beside the urtwin package")


def _override_list(overrides):
    if overrides is None:
        return []
    if isinstance(overrides, dict):
        out = []
        for k, v in overrides.items():
            if isinstance(v, bool):
                v = "true" if v else "false"
            elif isinstance(v, float):
                v = repr(v)
            out.append(f"{k}={v}")
        return out
    if isinstance(overrides, str):
        raise TypeError("overrides: expected a dict or a list of 'key=value' strings")
    return [str(s) for s in overrides]


class Model:
    """A loaded, validated robot model (urt_model_load_overlays).

    config: a parameter file (default config/ur5.yaml); overlays: overlay files applied in
    order; overrides: {key: value} or ["key=value", ...] (urt_sim's --set); rate: physics rate
    [Hz], which overrides simulation.dt last, as urt_sim --rate does."""

    def __init__(self, config=None, overlays=(), overrides=None, rate=None):
        self.config = str(config) if config is not None else default_config()
        self.overlays = [str(p) for p in overlays]
        self.overrides = _override_list(overrides)
        self.rate = rate
        sets = list(self.overrides)
        if rate is not None:
            rate = float(rate)
            if not np.isfinite(rate) or rate <= 0:
                raise ValueError(f"rate: expected a rate > 0 Hz, got {rate}")
            sets.append(f"simulation.dt={1.0 / rate!r}")
        self._m = _urtwin.Model(self.config, self.overlays, sets)

    def with_rate(self, rate):
        """The same model at another physics rate [Hz]."""
        return Model(self.config, self.overlays, self.overrides, rate)

    def print(self, json=False):
        """The fully resolved model as YAML (or JSON), as urt_sim --print-model writes it."""
        return self._m.print(json)

    dt = property(lambda self: self._m.dt)
    seed = property(lambda self: self._m.seed)
    name = property(lambda self: self._m.name)
    q0 = property(lambda self: np.array(self._m.q0))
    q_min = property(lambda self: np.array(self._m.q_min))
    q_max = property(lambda self: np.array(self._m.q_max))
    joint_names = property(lambda self: self._m.joint_names)
    payload_mass = property(lambda self: self._m.payload_mass)


def excitation(model, seed=1):
    """The random Fourier excitation of tools/traj.h from the model's q0 (urt_sim --traj
    excitation --seed SEED)."""
    return _urtwin.excitation(model._m, int(seed))


def pickplace(model):
    """The default pick-and-place of tools/traj.h (about 15 s)."""
    return _urtwin.pickplace(model._m)


def hold(model, duration=1.0):
    """Hold the model's q0 for duration seconds."""
    return _urtwin.hold(model._m, float(duration))


def from_arrays(t, q, qd=None, qdd=None):
    """A set-point from samples: t (n,) strictly increasing [s] (the run starts at t[0]),
    q (n, 6) [rad]; qd, qdd (n, 6) or None to derive them (second-order finite differences,
    np.gradient). Between samples q is a cubic Hermite on (q, qd), qd and qdd are linear; the
    arm starts at rest at q[0] (transient-free) and holds q[-1] after the end."""
    t = np.ascontiguousarray(t, dtype=np.float64)
    q = np.ascontiguousarray(q, dtype=np.float64)
    if t.ndim != 1 or t.shape[0] < 2:
        raise ValueError(f"t: expected a 1-D array of at least two times, got shape {t.shape}")
    n = t.shape[0]
    if q.shape != (n, NJ):
        raise ValueError(f"q: expected shape ({n}, {NJ}), got {q.shape}")
    if not np.all(np.isfinite(t)) or not np.all(np.diff(t) > 0):
        raise ValueError("t: expected finite, strictly increasing times")
    if not np.all(np.isfinite(q)):
        bad = int(np.argwhere(~np.isfinite(q))[0][0])
        raise ValueError(f"q: non-finite value at sample {bad}")
    if qd is None:
        qd = np.gradient(q, t, axis=0, edge_order=2 if n >= 3 else 1)
    qd = np.ascontiguousarray(qd, dtype=np.float64)
    if qdd is None:
        if qd.shape != (n, NJ):
            raise ValueError(f"qd: expected shape ({n}, {NJ}), got {qd.shape}")
        qdd = np.gradient(qd, t, axis=0, edge_order=2 if n >= 3 else 1)
    qdd = np.ascontiguousarray(qdd, dtype=np.float64)
    return _urtwin.samples(t, q, qd, qdd)


def read_record_csv(path):
    """An RTDE record.py recording (tools/replay_csv.h's checks): {name: array}, timestamp
    (n,), target_q, target_qd, actual_current (n, 6) and, when recorded, target_qdd,
    target_current, actual_q, actual_qd."""
    return _urtwin.read_record_csv(os.fspath(path))


def from_record_csv(path):
    """The recording's set-point (target_q, target_qd, and target_qdd when recorded) as a
    trajectory from its first timestamp. It goes to the drives directly, as from_arrays does;
    urt_sim --replay instead feeds it through the controller's interpolation."""
    rec = read_record_csv(path)
    return from_arrays(rec["timestamp"], rec["target_q"], rec["target_qd"],
                       rec.get("target_qdd"))


class Result:
    """A run's samples: result[name] is an (n,) or (n, 6) array (name in CHANNELS), .t the
    times, .info the steps taken and the loop's wall time."""

    def __init__(self, data, channels, info, model, trajectory):
        self.data = data
        self.channels = {c[0]: c for c in channels}
        self.info = dict(info)
        self.info["trajectory"] = trajectory.kind
        self.info["duration"] = float(data[-1, 0]) if len(data) else 0.0
        self.model = model

    def __getitem__(self, name):
        try:
            _, off, width, _, _ = self.channels[name]
        except KeyError:
            raise KeyError(f"{name!r}: not a channel (known: {', '.join(self.channels)})") \
                from None
        return self.data[:, off] if width == 1 else self.data[:, off:off + width]

    def __contains__(self, name):
        return name in self.channels

    def keys(self):
        return self.channels.keys()

    @property
    def t(self):
        return self["t"]

    def __len__(self):
        return self.data.shape[0]

    def unit(self, name):
        return self.channels[name][3]

    def csv_columns(self):
        """{column: (n,) array} with the names and order of urt_sim's CSV (t, then per joint
        j = 1..6 q_set_j q_j qd_j qm_j qdm_j i_j i_meas_j v_j tcs_j tf_j, then tcp_x … tcp_rz)."""
        out = {"t": self["t"]}
        for j in range(NJ):
            for c in ("q_set", "q", "qd", "qm", "qdm", "i", "i_meas", "v", "tcs", "tf"):
                out[f"{c}_{j + 1}"] = self[c][:, j]
        for k, c in enumerate(("x", "y", "z", "rx", "ry", "rz")):
            out[f"tcp_{c}"] = self["tcp"][:, k]
        return out


def run(model, trajectory, duration=None, seed=None, rate=None, decimate=1, traj_seed=1,
        faults=None):
    """Play trajectory through model and return a Result.

    trajectory: a Trajectory (excitation, pickplace, hold, from_arrays, from_record_csv) or
    the name of a built-in one ("excitation" with traj_seed, "pickplace", "hold"), built from
    the model's q0. duration [s]: default the trajectory's own (1 s for "hold"); afterwards
    the end is held. seed: the sensor-noise seed (default the model's simulation.seed; the
    same as the override simulation.seed=SEED). rate [Hz]: the physics rate (the model is
    reloaded with it). decimate: record every Nth step and the last. faults: a fault
    scenario (core/include/urt/faults.h) as a file path, YAML text, a dict {"faults": [...]}
    or a list of fault specs (dicts as the file spells them); installed at the start as
    `urt_sim --faults` does, a bad one raises ValueError "file:line: key: reason" (for a dict
    or list, "<faults>:line" of its YAML dump, yaml.safe_dump(..., sort_keys=False)). Every run
    records the truth channels fault_active_<class>, severity_<class> and health_index
    (CHANNELS says how they are formed), healthy runs too.
    The GIL is released while the run steps."""
    ffile, fyaml, fname = _fault_args(faults)
    if not isinstance(model, Model):
        raise TypeError("model: expected a urtwin.Model")
    if rate is not None:
        model = model.with_rate(rate)
    if isinstance(trajectory, str):
        if trajectory == "excitation":
            trajectory = excitation(model, traj_seed)
        elif trajectory == "pickplace":
            trajectory = pickplace(model)
        elif trajectory == "hold":
            trajectory = hold(model, duration if duration is not None else 1.0)
        else:
            raise ValueError(f"trajectory: expected excitation, pickplace, hold or a "
                             f"Trajectory, got {trajectory!r}")
    if not isinstance(trajectory, Trajectory):
        raise TypeError("trajectory: expected a urtwin.Trajectory or a built-in's name")
    if isinstance(decimate, bool) or int(decimate) != decimate or decimate < 1:
        raise ValueError(f"decimate: expected an integer >= 1, got {decimate!r}")
    if seed is not None and (int(seed) != seed or seed < 0 or seed >= 2**64):
        raise ValueError(f"seed: expected an unsigned 64-bit integer, got {seed!r}")
    dur = -1.0 if duration is None else float(duration)
    if duration is not None and not (np.isfinite(dur) and dur > 0):
        raise ValueError(f"duration: expected seconds > 0, got {duration!r}")
    data, chans, info = _urtwin.run(model._m, trajectory, dur, int(decimate),
                                    None if seed is None else int(seed), ffile, fyaml, fname)
    return Result(data, chans, info, model, trajectory)


# every channel a run records: (name, unit, what), in row order
CHANNELS = [(c[0], c[3], c[4]) for c in _urtwin.channels()]
