"""The population study (``bushenv zoo``): how often NARX bushing models fail, and why.

Many models per training recipe (``cell.py``: train, certify, judge, attack one), their failure
rates with 95 % intervals (``summary.py``), the study (``study.py``). With ``--env rig3`` the
MIMO population: planar networks given the single-axis check, then the attack across axes
(``planar_cell.py``, ``planar_summary.py``, ``planar_study.py``).
"""
