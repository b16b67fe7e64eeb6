"""Gravity's joint torques on a spatial arm, against the potential energy's gradient.

``tau = -dV/du`` with ``V = -sum_k m_k g . c_k`` (J, centres in metres), by central
differences of step 1e-6 (rad, mm): their error is about ``h^2 |V'''|`` (1e-12 of
a few hundred J) plus ``eps |V| / h`` (1e-16 x 1e3 / 1e-6 = 1e-7 N m), so 1e-6
relative to the largest torque is safe.  A prismatic joint's value is in mm: its
force is ``-1000 dV/du``.
"""

from __future__ import annotations

import numpy as np
import pytest

from armcal.models.spatial.chain import joint_motion
from armcal.models.spatial.gravity import STANDARD_GRAVITY, LinkMasses, gravity_torques
from helpers import central_differences
from helpers_spatial import ARMS, random_poses


def _energy(chain, u, links, g, payload_kg, payload_com):
    """``V`` (J) of the links and the payload at joint values ``u`` ``(n,)``."""
    frame, total = np.eye(4), 0.0
    for k, kind in enumerate(chain.kinds):
        frame = frame @ chain.origins[k] @ joint_motion(kind, u[k])
        centre = frame[:3, :3] @ links.com_mm[k] + frame[:3, 3]
        total -= links.mass_kg[k] * g @ centre / 1000.0
    tip = frame @ chain.tip
    return total - payload_kg * g @ (tip[:3, :3] @ payload_com + tip[:3, 3]) / 1000.0


@pytest.mark.parametrize("name", sorted(ARMS))
def test_gravity_torques_are_the_potential_energy_s_gradient(name):
    arm = ARMS[name]()
    chain, n = arm.chain, arm.n_joints
    rng = np.random.default_rng(21)
    links = LinkMasses(rng.uniform(1.0, 80.0, n), rng.uniform(-300.0, 300.0, (n, 3)))
    g = np.array([0.3, -0.2, -STANDARD_GRAVITY])  # a frame slightly off level
    payload, at = 12.0, np.array([20.0, -10.0, 150.0])
    u = random_poses(arm, 4, rng) @ arm.joint_map.T
    found = gravity_torques(chain, u, links, g, payload_kg=payload, payload_com_mm=at)
    scale = np.where(np.array(chain.kinds) == "P", 1000.0, 1.0)
    for pose, torques in zip(u, found, strict=True):
        numeric = (
            -scale
            * central_differences(
                lambda x: np.array([_energy(chain, x, links, g, payload, at)]), pose
            )[0]
        )
        np.testing.assert_allclose(torques, numeric, rtol=0, atol=1e-6 * np.max(np.abs(numeric)))
