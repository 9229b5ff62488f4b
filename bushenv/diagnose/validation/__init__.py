"""Blind validation of the gap diagnosis (``bushenv diagnose-validate``).

``validate.py`` runs the cases and scores the answers; the rest generate the cases from a seed:
the reference rubber with known effects (``reference_cases.py``), forms, programmes, rates and
noise the candidates do not assume (``widened_cases.py``, ``truth_forms.py``,
``widened_programmes.py``) and effects outside the candidates (``outside_cases.py``); single
effects and pairs in forms no candidate shares (``partner_cases.py``), three-axis cases
(``three_axis_cases.py``), a thermal session to tell from relaxation (``thermal_session.py``)
and the records the diagnosis is timed on (``timing_cases.py``). The diagnosis itself
(``bushenv.diagnose``) never imports from here.
"""
