"""Reports over results directories: leaderboards, comparisons, plots and the
HTML report (the paper reproduction report is :mod:`touchbench.papers`).

- :mod:`.results`: read and combine results directories (methods identified
  by their parameters' hash, machines by their platform);
- :mod:`.stats`: intervals, paired tests (exact permutation / Wilcoxon), Holm;
- :mod:`.pareto`: the accuracy / cost Pareto front;
- :mod:`.leaderboard`: one table per dataset, target and scheme; compare;
- :mod:`.plots`: Pareto, accuracy vs frames, confusion, per-subject (PNG + SVG);
- :mod:`.html`: one self-contained HTML page.
"""
