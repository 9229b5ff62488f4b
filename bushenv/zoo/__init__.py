"""The population study (``bushenv zoo``): how often NARX bushing models fail, and why.

Many models per training recipe (``cell.py``: train, certify, judge, attack one), their failure
rates with 95 % intervals (``summary.py``), and the command (``command.py``).
"""
