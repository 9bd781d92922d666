"""Reports over results directories: leaderboards, comparisons, plots, the
HTML report and the paper reproduction report.

- :mod:`.results`: read and combine results directories (methods identified
  by their parameters' hash, machines by their platform);
- :mod:`.stats`: intervals, paired tests (exact permutation / Wilcoxon), Holm;
- :mod:`.pareto`: the accuracy / cost Pareto front;
- :mod:`.leaderboard`: one table per dataset, target and scheme; compare;
- :mod:`.plots`: Pareto, accuracy vs frames, confusion, per-subject (PNG + SVG);
- :mod:`.html`: one self-contained HTML page;
- :mod:`.papers`: ``touchbench papers reproduce`` and ``REPORT.md``.
"""
