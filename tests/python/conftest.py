# SPDX-License-Identifier: Apache-2.0
"""Shared fixtures: the urtwin shared library, the UR5 model loaded through it, and the same
model's resolved parameters from urt_config. A missing build artefact fails (built.py)."""

import os

import pytest

import built
import urtwin_ctypes as urt


@pytest.fixture(scope="session")
def urtwin_lib():
    if not os.path.exists(urt.LIBURTWIN):
        pytest.fail(f"{urt.LIBURTWIN} is not built (set URT_BUILD to the cmake build dir)",
                    pytrace=False)
    return urt.load_library()


@pytest.fixture(scope="session")
def ur5(urtwin_lib):
    with urt.Model(urtwin_lib, urt.UR5_YAML) as m:
        yield m


@pytest.fixture(scope="session")
def ur5_params():
    built.require(urt.URT_CONFIG)
    return urt.resolved_model(urt.UR5_YAML)
