# SPDX-License-Identifier: Apache-2.0
"""Reader of robot recordings in the column layout of UR's RTDE record.py: one header line of
space-separated names, then one sample per line. Vector fields carry a _0 … _5 suffix per joint.

read_recording(path) returns a Recording; a bad file raises RecordingError with
"file:line: reason" (urt_identify.py turns that into exit status 2)."""

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

NJ = 6
# what the identification needs, and what it uses when present
REQUIRED = ("target_q", "target_qd", "target_qdd", "actual_current")
OPTIONAL = ("target_current", "target_moment", "actual_q", "actual_qd")
# other standard record.py output names (joint vectors unless listed as scalar or 3/6-vectors)
OTHER_VECTORS = ("joint_control_output", "actual_joint_voltage", "joint_temperatures",
                 "joint_mode", "target_speed_fraction", "actual_TCP_pose", "actual_TCP_speed",
                 "actual_TCP_force", "target_TCP_pose", "target_TCP_speed",
                 "actual_tool_accelerometer", "elbow_position", "elbow_velocity")
SCALARS = ("timestamp", "robot_mode", "safety_mode", "runtime_state", "speed_scaling",
           "actual_momentum", "actual_main_voltage", "actual_robot_voltage",
           "actual_robot_current", "actual_execution_time", "actual_digital_input_bits",
           "actual_digital_output_bits", "tool_mode", "output_int_register_0")


class RecordingError(Exception):
    """A recording that cannot be used; the message reads file:line: reason."""


@dataclass
class Recording:
    path: Path
    t: np.ndarray                      # [s], strictly increasing
    cols: dict = field(default_factory=dict)  # name -> (n, 6) array for joint vectors

    def __getitem__(self, name):
        return self.cols[name]

    def has(self, name):
        return name in self.cols


def _known(name):
    if name in SCALARS:
        return True
    base, _, idx = name.rpartition("_")
    return idx.isdigit() and int(idx) < NJ and base in REQUIRED + OPTIONAL + OTHER_VECTORS


def read_recording(path):
    path = Path(path)
    try:
        lines = path.read_text().splitlines()
    except OSError as e:
        raise RecordingError(f"{path}: cannot open: {e.strerror}") from None
    if not lines or not lines[0].strip():
        raise RecordingError(f"{path}:1: empty file (expected a header line)")
    names = lines[0].split()
    seen = {}
    for name in names:
        if not _known(name):
            raise RecordingError(f"{path}:1: unknown column '{name}'")
        if name in seen:
            raise RecordingError(f"{path}:1: duplicate column '{name}'")
        seen[name] = len(seen)
    for need in ("timestamp",) + tuple(f"{b}_{j}" for b in REQUIRED for j in range(NJ)):
        if need not in seen:
            raise RecordingError(f"{path}:1: missing required column '{need}'")

    rows = []
    for k, line in enumerate(lines[1:], start=2):
        if not line.strip():
            continue
        cells = line.split()
        if len(cells) != len(names):
            raise RecordingError(f"{path}:{k}: {len(cells)} cells, header has {len(names)}")
        try:
            row = [float(c) for c in cells]
        except ValueError:
            bad = next(c for c in cells if not _is_float(c))
            raise RecordingError(f"{path}:{k}: non-numeric cell '{bad}'") from None
        if not all(np.isfinite(row)):
            raise RecordingError(f"{path}:{k}: non-finite cell")
        if rows and row[seen["timestamp"]] <= rows[-1][0][seen["timestamp"]]:
            raise RecordingError(f"{path}:{k}: timestamp {row[seen['timestamp']]} does not "
                                 f"increase (previous {rows[-1][0][seen['timestamp']]})")
        rows.append((row, k))
    if len(rows) < 10:
        raise RecordingError(f"{path}: {len(rows)} samples, need at least 10")
    data = np.array([r for r, _ in rows])
    rec = Recording(path=path, t=data[:, seen["timestamp"]])
    for base in REQUIRED + OPTIONAL:
        if all(f"{base}_{j}" in seen for j in range(NJ)):
            rec.cols[base] = np.stack([data[:, seen[f"{base}_{j}"]] for j in range(NJ)], axis=1)
    return rec


def _is_float(s):
    try:
        float(s)
        return True
    except ValueError:
        return False


def write_recording(path, t, cols):
    """Write t and the joint vectors in cols ({name: (n, 6)}) in the record.py layout."""
    names = ["timestamp"] + [f"{b}_{j}" for b in cols for j in range(NJ)]
    data = np.column_stack([t] + [np.asarray(cols[b]) for b in cols])
    with open(path, "w") as f:
        f.write(" ".join(names) + "\n")
        for row in data:
            f.write(" ".join(f"{v:.9g}" for v in row) + "\n")
