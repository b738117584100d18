"""Sensitivity screening of forward-model parameters (thesis §3.4, Algorithm 1, Fig. 3.2).

* :mod:`.table_3_1` -- the 19-parameter space of Table 3.1, grouped by sub-model;
* :mod:`.sobol_screening` / :mod:`.morris_screening` -- the ``sobol_screening`` and ``morris_screening`` stages;
* :mod:`.selected_space` -- the ``selected_space`` stage (screening result -> reduced SPACE);
* :mod:`.figure` -- Fig. 3.2-style bar charts of total indices per sub-model.
"""
