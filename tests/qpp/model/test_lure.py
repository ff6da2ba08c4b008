"""The Lure plant and its closed loop (qpp.model.lure, eq 10.7): eq 13.6 and Table 14.1 rebuilt
from the printed gains; N = G⁺B without round-off; the structural obstacles of a plant."""
import numpy as np
import pytest

from qpp.model.lure import closed_loop
from qpp.io.config import parse_config

from tests.qpp.conftest import _base, _pub

SISO_AZ = np.array([  # eq 13.6 as printed
    [0., 1., 0., 0., 0., 0.],
    [0., -1., 2506.2, 1937.1, -299.9, -23.5],
    [0., 0., 0., 1., 0., 0.],
    [-1., 0., -25., 0., 0., 0.],
    [0.1, 0., 0., 0., -0.1, 1.],
    [0., 0., 2506.2, 1937.1, -299.9, -24.5]])
SISO_BZ = np.array([[0, 0], [0, 0.1], [0, 0], [1, 0], [-0.0955, 0], [-0.0046, 0]])
T141 = np.array([  # Table 14.1, A_z / 1e3, columns 1-8 then 9-11
    [0, 0, .001, 0, 0, 0, 0, 0, 0, 0, 0],
    [0, 0, 0, .001, 0, 0, 0, 0, 0, 0, 0],
    [0, 0, 0, 0, 1.0204, 0, 0, -.2029, 0, -.0202, 0],
    [0, 0, 0, 0, 0, 1.0059, .4669, 0, -.1084, 0, -.0147],
    [-.001, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0],
    [0, 0, 0, 0, 0, 0, .001, 0, 0, 0, 0],
    [0, -.001, 0, 0, 0, 0, 0, 0, 0, 0, 0],
    [.0005, 0, 0, 0, 0, 0, 0, -.0005, 0, .001, 0],
    [0, .0005, 0, 0, 0, 0, 0, 0, -.0005, 0, .001],
    [.0001, 0, 0, 0, 1.0204, 0, 0, -.2030, 0, -.0202, 0],
    [0, .0001, 0, 0, 0, 1.0059, .4669, 0, -.1085, 0, -.0147]])
T141_BZ = np.zeros((11, 4))
T141_BZ[2, 2] = T141_BZ[3, 3] = 0.1
T141_BZ[4, 0] = T141_BZ[6, 1] = 1.0
T141_BZ[7:, :2] = [[-.4571, 0], [0, -.4501], [-.1022, 0], [0, -.1007]]


def test_siso_Az_rebuilt_from_printed_gains(siso):
    Az, Bz, Cz = closed_loop(siso.lure_plant(), *_pub(siso), bz="printed")
    np.testing.assert_array_equal(np.round(Az, 1) + 0.0, SISO_AZ)
    np.testing.assert_array_equal(Bz, SISO_BZ)
    np.testing.assert_array_equal(Cz, [[1, 0, 0, 0, 0, 0]])
    _, Bz107, _ = closed_loop(siso.lure_plant(), *_pub(siso), bz="eq10.7")
    assert np.all(Bz107[4:] == 0)


def test_table_14_1_rebuilt_from_printed_gains(arm):
    Az, Bz, Cz = closed_loop(arm.lure_plant(), *_pub(arm), bz="printed")
    np.testing.assert_array_equal(np.round(Az / 1e3, 4) + 0.0, T141)
    np.testing.assert_array_equal(Bz, T141_BZ)


def test_round_off_in_N_does_not_couple_the_phi_channels():
    """B = G with a column that lstsq returns with 1e-16 off-diagonal entries: N is I exactly, so
    each φ_i depends on its own output only (one-sided sectors stay one-sided)."""
    data = _base(**{"plant.A": [[0, 1, 0, 0], [-2, -1, 0, 0], [0, 0, 0, 1], [0, 0, -3, -2]],
                    "plant.B": [[0, 0], [0, 0], [1, 0.5], [0, 1]], "plant.G": [[0, 0], [0, 0], [1, 0.5], [0, 1]],
                    "plant.C": [[1, 0, 0, 0], [0, 0, 1, 0]], "plant.Ac": [[0, 0], [0, 0]],
                    "plant.Bc": [[1, 0], [0, 1]], "plant.Cc": [[1, 0], [0, 1]],
                    "nonlinearity.f1": ["k*sat(y1, 0.4)", "k*sat(y2, 0.4)"],
                    "nonlinearity.parameters": {"k": {"min": 0.0, "max": 0.5, "nominal": 0.0}},
                    "nonlinearity.y_range": [[-2, 2], [-2, 2]],
                    "simulation.r_o": [[{"kind": "step", "amplitude": 0.1}], [{"kind": "step", "amplitude": 0.0}]]})
    cfg = parse_config(data)
    N = cfg.lure_plant().N()
    np.testing.assert_array_equal(N, np.eye(2))
    info = cfg.expression_model().sector_info
    assert info.diagonal.all()
    np.testing.assert_allclose(info.sector, [[0.0, 0.5], [0.0, 0.5]], atol=1e-9)


@pytest.mark.parametrize("plant, words", [
    (([[1, 0], [0, -2]], [[0], [1]], [[1, 1]]), "not controllable from u"),
    (([[1, 0], [0, -2]], [[1], [1]], [[0, 1]]), "not observable from y"),
    (([[0, 1], [2, -1]], [[0], [1]], [[1, -1]]), "not observable from y"),        # zero cancels the pole
    (([[0, 1], [-1, -0.5]], [[0], [1]], [[0, 1]]), "servo-compensator's pole at s = 0"),
])
def test_a_structurally_impossible_plant_names_its_obstacle(plant, words):
    """No gains of eqs 10.5–10.6 exist: the failure says why (PBH tests), not only that none was found."""
    from qpp.model.lure import LurePlant, structural_obstacles

    A, B, C = plant
    why = structural_obstacles(LurePlant(A, B, C, B, [[0]], [[1]], [[1]]))
    assert len(why) == 1 and words in why[0]
    # the same structure without the obstacle (C = [2, −1]: observable, no zero at 0) has none
    assert structural_obstacles(LurePlant([[0, 1], [2, -1]], [[0], [1]], [[2, -1]], [[0], [1]],
                                          [[0]], [[1]], [[1]])) == []


def test_a_badly_scaled_plant_has_no_false_obstacle():
    """A = [[0, 1e6], [0, 0]], B = [0; 1e-4]: controllable (rank 2), observable from y = x1, no
    zero at the integrator's pole; a rank test relative to max|A| called it uncontrollable."""
    from qpp.model.lure import LurePlant, structural_obstacles

    A, B, C = np.array([[0.0, 1e6], [0.0, 0.0]]), np.array([[0.0], [1e-4]]), np.array([[1.0, 0.0]])
    assert np.linalg.matrix_rank(np.hstack([B, A @ B])) == 2                   # independent: Kalman rank
    assert structural_obstacles(LurePlant(A, B, C, B, [[0]], [[1]], [[1]])) == []
