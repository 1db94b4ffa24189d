# SPDX-License-Identifier: Apache-2.0
"""Smoke test of tools/bench_dds.py (make bench): both runs happen, the C probes receive
joint states only when DDS is on, and the JSON has every figure the report quotes."""
import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent.parent


def test_bench_dds__off_and_on_with_probes(tmp_path):
    out = tmp_path / "bench_dds.json"
    env = dict(os.environ, URT_BUILD=os.environ.get("URT_BUILD", str(ROOT / "build")))
    r = subprocess.run([sys.executable, str(ROOT / "tools" / "bench_dds.py"), "--seconds", "3",
                        "--probes", "2", "--host", "127.0.0.62", "--out", str(out)],
                       capture_output=True, text=True, timeout=180, env=env)
    assert r.returncode == 0, r.stderr[-2000:]
    d = json.loads(out.read_text())
    assert d["off"]["dds"] is False and d["on"]["dds"] is True
    assert all(p["samples"] == 0 for p in d["off"]["per_probe"])
    assert all(p["samples"] > 500 for p in d["on"]["per_probe"]), d["on"]["per_probe"]
    for k in ("ticks", "overruns", "missed_periods"):
        assert isinstance(d["off"][k], int) and isinstance(d["on"][k], int)
    assert d["on"]["latency_us"]["p50_us"] > 0 and d["on"]["latency_us"]["p99_us"] >= \
        d["on"]["latency_us"]["p50_us"]
    assert "tick->subscriber latency" in r.stdout
