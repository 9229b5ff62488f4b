"""What the export tests share: bushenv excitations and the set-then-read master."""

from bushenv import excitation as ex
from bushenv.export.fmpy_master import set_then_read  # noqa: F401  (re-exported)
from bushenv.models import PAPER_DT

AXIS = {"linear": "axial", "nn": "axial", "hybrid": "axial", "boucwen": "radial"}


def inputs():
    """Excitations from bushenv: (name, x) at the papers' rate."""
    dt = PAPER_DT
    return {
        "random n=1": ex.random_rpc(1.0, 4.0, dt, seed=0),
        "4 mm step": ex.step_hold(4e-3, 1.0, dt),
        "sines": ex.sine(2.0, 3e-3, 1.0, dt) + ex.sine(23.0, 0.4e-3, 1.0, dt),
    }
