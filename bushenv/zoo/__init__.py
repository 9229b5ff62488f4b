"""The population study (``bushenv zoo``): how often NARX bushing models fail, and why.

Many models per training recipe, over the target's number of coordinates (``cell.py``: train,
judge, check the holds, attack one member; ``holds.py``, ``attack.py``), their failure rates
with 95 % intervals (``rates.py``, ``summary.py``, ``tables.py``), the study (``study.py``).
With ``--env rig3`` the MIMO population: networks over three coordinates given the
single-axis check, then the attack across axes.
"""
