"""Evaluation schemes: splitters over the metadata table, one module per scheme.

Each scheme of the four papers is one registered splitter (``SPLITTERS``),
in the module of this package named for it; :mod:`.base` holds what they
share (:class:`Splitter`, :class:`Fold`, the registry, which finds the
schemes by importing every module of this package):

==========================  ====================================================
``challenge``               fixed train/test from a split column or subject
                            lists (Gaus et al. 2015, Sec. 4: the Social Touch
                            Gesture Challenge split).
``loso``                    leave one subject out (Al-mashhadani et al. 2021,
                            Sec. 3, Table 2; optionally only some subjects are
                            held out, as for their Fig. 5).
``kfold``                   (stratified) k-fold with repeats, optionally
                            grouped so no subject is on both sides (Gaus Sec. 4:
                            10-fold; Flagg 2012 Sec. 4.4: 100-fold; Zhou et al.
                            2017 Sec. 5: 5-fold "random cross-validation").
``within-subject``          k-fold inside each subject, one model per subject,
                            scores per subject (Flagg Sec. 4.4, Fig. 4.5).
``leave-recording-out``     train on one recording of every person, test on the
                            other, then swap (Zhou Sec. 5.4, Fig. 9b).
``person-independent``      subjects dealt into k disjoint parties, each tested
                            once (Zhou Sec. 5.4: 4 parties of 6, Fig. 9c).
``transfer``                train on one group, test on another, both
                            directions (Zhou Sec. 5.4, Fig. 11: A->B, B->A).
``window-kfold``            k-fold over windows cut from the captures, the
                            windows the samples (leaky unless grouped by
                            subject: windows of one capture on both sides).
``cross-dataset``           train on one dataset, test on another (adapted to
                            the training sensor when declared).
``multi-source``            train on one dataset and the other subjects of
                            another, test each subject of the other in turn.
``early``                   any scheme above, with test captures (optionally
                            training captures too) cut to their first N frames
                            or S seconds, N swept over a list (Al-mashhadani
                            Sec. 2.3: recognition after the first frames).
``learning-curve``          any scheme keeping subjects apart, each fold trained
                            on n of its training subjects (drawn at random,
                            ``draws`` distinct subsets), n swept, plus the
                            full point; the base fold's test captures.
``calibration``             any scheme, k labelled captures per class of each
                            test subject (``unit``) joining training, k swept
                            from 0; the largest-k pool is never scored.
==========================  ====================================================

A scheme that lets the test data inform training says why in
``leakage()`` (k-fold ignoring subjects when the target is not the subject,
window-level k-fold): the engine writes it into every result row and the
reports flag it; no such scheme is a default. A scheme that changes the
data (``window-kfold``, ``cross-dataset``) does it in ``prepare``. A scheme
whose folds each test one fixed set of captures whatever the seed
(``challenge``, ``transfer``, ``cross-dataset``: ``Splitter.single_test_set``)
is run with ``DEFAULT_SEEDS`` repetitions (seeds of every method) unless the
protocol sets ``repetitions``.

``folds(meta)`` returns a list of :class:`Fold`; ``split(X, y, groups)``
and ``get_n_splits`` give the same folds to scikit-learn
(``cross_val_score(..., cv=make_splitter("loso"))``).
"""

from __future__ import annotations

from .base import (DEFAULT_SEEDS, SPLITTERS, Crop, CurvePoint, DataContext, Fold, SplitError, Splitter, curve_columns,
                   fold_notes, make_splitter)

__all__ = [
    "DEFAULT_SEEDS",
    "SPLITTERS",
    "Crop",
    "CurvePoint",
    "DataContext",
    "Fold",
    "SplitError",
    "Splitter",
    "curve_columns",
    "fold_notes",
    "make_splitter",
]
