"""Reports over results directories: leaderboards, comparisons, plots and the
HTML report (the paper reproduction report is :mod:`touchbench.papers`).

- :mod:`.results`: read and combine results directories (methods identified
  by their parameters' hash, machines by their platform);
- :mod:`.stats`: intervals, paired tests (exact permutation / Wilcoxon), Holm;
- :mod:`.pareto`: the accuracy / cost Pareto front;
- :mod:`.leaderboard`: one table per dataset, target and scheme (:mod:`.paired`: the
  paired tests; :mod:`.labels`: how rows read); :mod:`.across`: across tables;
  :mod:`.compare`: two methods; :mod:`.rendering`: terminal, Markdown, CSV, JSON;
- :mod:`.figures`: the figure kinds, one module each (``FIGURES``): Pareto, accuracy vs
  frames, confusion, per-subject, critical difference (PDF, SVG, PNG);
- :mod:`.html`: one self-contained HTML page.
"""
