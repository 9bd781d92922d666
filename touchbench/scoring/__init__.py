"""Scores: the metrics of a task's predictions (``metrics``), the frame-by-frame scores of a
replayed stream (``streams``) and how faithful a synthetic scene is to the real data it stands for
(``fidelity``)."""
