"""The PBH controllability of the 24-state design model (acmm.model.controllability): the AC
model is controllable, the decoupled MB3 design model nearly uncontrollable."""
from acmm.io.config import load_config
from acmm.model.linearize import linearize_config
from acmm.model.controllability import controllability


def test_statespace_view_and_controllability():
    cfg = load_config("ac")
    m = linearize_config(cfg)
    sys = m.to_statespace()
    assert sys.nstates == 24 and sys.ninputs == 6
    assert list(sys.state_labels) == list(m.state_names)
    c = controllability(m)
    assert c.rank == 24
    # decoupled MB3 design model is nearly uncontrollable (docs/ERRATA.md § Sector LQR; ≈5e-9 at s = 0)
    cfg_d = load_config("mb3_decoupled")
    c_d = controllability(linearize_config(cfg_d))
    assert c_d.min_ratio < 1e-6
