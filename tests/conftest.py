"""Shared fixtures: the paper's arms and a seeded random generator."""

import numpy as np
import pytest

from armcal import PlanarArm, load_robot


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20261121)


@pytest.fixture
def arm2() -> PlanarArm:
    return load_robot("paper-2link").arm


@pytest.fixture
def arm4() -> PlanarArm:
    return load_robot("paper-4link").arm


@pytest.fixture
def paper_truth4() -> np.ndarray:
    return load_robot("paper-4link").default_truth
