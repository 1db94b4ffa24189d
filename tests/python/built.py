# SPDX-License-Identifier: Apache-2.0
"""What make test builds before pytest runs: a missing binary is a broken build, so it fails the
file instead of skipping it (a skipped file still counts as run in tools/check_tests_ran.py, so a
skip here could let a whole file's tests vanish from CI). Only ../shared's absence may skip."""

import os

import pytest


def require(*paths):
    """Fail the calling test module (at collection) unless every path is an executable file."""
    for p in paths:
        if not os.access(p, os.X_OK):
            pytest.fail(f"{p} is not built: run make build (or set URT_BUILD)", pytrace=False)
