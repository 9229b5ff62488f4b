"""Every registered target through every check of the target contract
(``bushenv.search.checks``): registering a target is the one step that tests it."""

import numpy as np
import pytest

from bushenv.search.checks import TARGET_CHECKS
from bushenv.search.targets import TARGETS, RigTarget


@pytest.mark.parametrize("check", sorted(TARGET_CHECKS))
@pytest.mark.parametrize("name", TARGETS.names())
def test_every_registered_target_keeps_the_contract(name, check):
    TARGET_CHECKS[check](TARGETS[name])


class Unclipped(RigTarget):
    """A rig whose shrinking moves may leave the stroke: ``finish`` forgets the limits."""

    def finish(self, x, dt, limits=None):
        return np.asarray(x) * 1.5  # the bug: scaled past the stroke


def test_the_checks_catch_a_target_whose_moves_leave_its_limits():
    with TARGETS.temporarily("unclipped", Unclipped()):
        target = TARGETS["unclipped"]
        TARGET_CHECKS["families_keep_the_env_limits"](target)  # its families are the rig's
        with pytest.raises(AssertionError, match=r"shrinking move \d+: (\|x\| reaches|rate)"):
            TARGET_CHECKS["shrink_moves_keep_profiles_valid"](target)
