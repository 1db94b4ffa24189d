# SPDX-License-Identifier: Apache-2.0
"""ctypes access to liburtwin.so for the Python cross-checks.

The model is an opaque pointer: urt_model_load() fills it from a parameter file and
urt_model_free() releases it. Arrays cross the boundary as C doubles; results come back as
numpy arrays (row-major 6×6 matrices as numpy 6×6).
"""

import ctypes
import json
import os
import subprocess
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
BUILD = Path(os.environ.get("URT_BUILD", ROOT / "build"))
LIBURTWIN = BUILD / "core" / "liburtwin.so"
URT_CONFIG = BUILD / "tools" / "urt_config"
UR5_YAML = ROOT / "config" / "ur5.yaml"

NJ = 6
_D6 = ctypes.c_double * NJ
_D16 = ctypes.c_double * 16
_D36 = ctypes.c_double * 36


def _arr(x, n):
    x = np.ascontiguousarray(x, dtype=np.float64)
    if x.shape != (n,):
        raise ValueError(f"expected {n} values, got shape {x.shape}")
    return (ctypes.c_double * n)(*x)


def load_library(path=LIBURTWIN):
    """Open liburtwin.so and declare the signatures used by the tests."""
    lib = ctypes.CDLL(str(path))
    p = ctypes.c_void_p
    dp = ctypes.POINTER(ctypes.c_double)
    lib.urt_model_load.argtypes = [ctypes.c_char_p, ctypes.POINTER(ctypes.c_char_p),
                                   ctypes.POINTER(p),
                                   ctypes.c_char_p, ctypes.c_size_t]
    lib.urt_model_load.restype = ctypes.c_int
    lib.urt_model_load_overlays.argtypes = [ctypes.c_char_p, ctypes.POINTER(ctypes.c_char_p),
                                            ctypes.POINTER(ctypes.c_char_p), ctypes.POINTER(p),
                                            ctypes.c_char_p, ctypes.c_size_t]
    lib.urt_model_load_overlays.restype = ctypes.c_int
    lib.urt_config_key_unit.argtypes = [ctypes.c_char_p]
    lib.urt_config_key_unit.restype = ctypes.c_char_p
    lib.urt_model_free.argtypes = [p]
    lib.urt_model_free.restype = None
    for name, nargs in (("urt_arm_tcp_pose", 2), ("urt_arm_jacobian", 2),
                        ("urt_arm_mass_matrix", 2), ("urt_arm_gravity", 2),
                        ("urt_arm_rnea", 4), ("urt_arm_forward_dynamics", 4)):
        fn = getattr(lib, name)
        fn.argtypes = [p] + [dp] * nargs
        fn.restype = None
    lib.urt_arm_frame.argtypes = [p, dp, ctypes.c_int, dp]
    lib.urt_arm_frame.restype = None
    lib.urt_arm_energy.argtypes = [p, dp, dp]
    lib.urt_arm_energy.restype = ctypes.c_double
    return lib


class Model:
    """A model loaded through urt_model_load_overlays() (overlay files, then "key=value"
    overrides); use as a context manager or call close()."""

    def __init__(self, lib, path=UR5_YAML, overrides=(), overlays=()):
        self.lib = lib
        self.ptr = ctypes.c_void_p()
        err = ctypes.create_string_buffer(512)

        def c_list(items):
            # NULL-terminated, as the loader takes them
            if not items:
                return None
            return (ctypes.c_char_p * (len(items) + 1))(*[str(o).encode() for o in items], None)

        rc = lib.urt_model_load_overlays(str(path).encode(), c_list(overlays), c_list(overrides),
                                         ctypes.byref(self.ptr), err, ctypes.sizeof(err))
        if rc != 0 or not self.ptr:
            raise RuntimeError(f"urt_model_load({path}) = {rc}: {err.value.decode()}")

    def close(self):
        if self.ptr:
            self.lib.urt_model_free(self.ptr)
            self.ptr = ctypes.c_void_p()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # ---- urt_arm_* ----

    def tcp_pose(self, q):
        out = _D6()
        self.lib.urt_arm_tcp_pose(self.ptr, _arr(q, NJ), out)
        return np.array(out)

    def frame(self, q, i):
        out = _D16()
        self.lib.urt_arm_frame(self.ptr, _arr(q, NJ), i, out)
        return np.array(out).reshape(4, 4)

    def jacobian(self, q):
        out = _D36()
        self.lib.urt_arm_jacobian(self.ptr, _arr(q, NJ), out)
        return np.array(out).reshape(6, 6)

    def mass_matrix(self, q):
        out = _D36()
        self.lib.urt_arm_mass_matrix(self.ptr, _arr(q, NJ), out)
        return np.array(out).reshape(6, 6)

    def gravity(self, q):
        out = _D6()
        self.lib.urt_arm_gravity(self.ptr, _arr(q, NJ), out)
        return np.array(out)

    def rnea(self, q, qd, qdd):
        out = _D6()
        self.lib.urt_arm_rnea(self.ptr, _arr(q, NJ), _arr(qd, NJ), _arr(qdd, NJ), out)
        return np.array(out)

    def forward_dynamics(self, q, qd, tau):
        out = _D6()
        self.lib.urt_arm_forward_dynamics(self.ptr, _arr(q, NJ), _arr(qd, NJ), _arr(tau, NJ),
                                          out)
        return np.array(out)

    def energy(self, q, qd):
        return self.lib.urt_arm_energy(self.ptr, _arr(q, NJ), _arr(qd, NJ))


def resolved_model(path=UR5_YAML, overrides=(), tool=URT_CONFIG):
    """The fully resolved model as printed by `urt_config --print --json` (SI units), with the
    same "key.path=value" overrides urt_model_load() takes."""
    sets = [arg for o in overrides for arg in ("--set", o)]
    out = subprocess.run([str(tool), "--print", "--json", *sets, str(path)], check=True,
                         capture_output=True, text=True)
    return json.loads(out.stdout)
