"""Every registered classifier's declared parameter domains (``_parameter_constraints``) reach a
protocol: a value just beyond a bound is refused by ``parse_protocol`` at its field, naming the
bound; the value at the bound is accepted. The bounds below are read off each class's declared
domain (and its docstring's reasons) by hand, not from the code's output; a method's parameters go
to its estimator, a wrapper's ``params`` to its inner estimator."""

from __future__ import annotations

import pytest

from touchbench.core.errors import TouchbenchError
from touchbench.core.versions import missing_extra
from touchbench.protocols.loading import parse_protocol

HEAD = "name: x\ndataset: scene:tiny\nscheme: loso\nseed: 1\n"


def _needs(extra: str | None):
    return [pytest.mark.skipif(bool(extra and missing_extra(extra)), reason=f"needs the {extra} extra")]


def _refusal(entry: str, params: str, section: str = "methods") -> str:
    """The message ``parse_protocol`` refuses the one-entry protocol with ("" when it accepts it)."""
    text = HEAD + ("features: [[flagg-stats]]\n" if section == "classifiers" else "")
    text += f"{section}:\n  - name: {entry}\n    params: {params}\n"
    try:
        parse_protocol(text, "p.yaml")
    except TouchbenchError as e:
        return str(e)
    return ""


#: (entry, optional extra, field, value beyond a bound, words the refusal says: the bound)
BEYOND = [
    # the aeon peers: aeon turns n_kernels < 84 into 84 (MiniRocket) or divides by zero (MultiRocket)
    ("minirocket", "peers", "n_kernels", "83", "[84, 100000]"),
    ("minirocket", "peers", "n_kernels", "100001", "[84, 100000]"),
    ("minirocket", "peers", "max_dilations_per_kernel", "0", "[1, inf)"),
    ("minirocket", "peers", "n_jobs", "0", "[1, inf), an int in the range (-inf, -1] or None"),
    ("minirocket", "peers", "length", "0", "[1, inf)"),
    ("multirocket", "peers", "n_kernels", "83", "[84, 100000]"),
    ("multirocket", "peers", "n_kernels", "100001", "[84, 100000]"),
    ("multirocket-hydra", "peers,deep", "n_kernels", "0", "[1, 128]"),
    ("multirocket-hydra", "peers,deep", "n_kernels", "129", "[1, 128]"),
    ("multirocket-hydra", "peers,deep", "n_groups", "1025", "[1, 1024]"),
    ("quant", "peers,deep", "interval_depth", "0", "[1, 16]"),
    ("quant", "peers,deep", "interval_depth", "17", "[1, 16]"),
    ("quant", "peers,deep", "quantile_divisor", "0", "[1, inf)"),
    ("rdst", "peers", "max_shapelets", "0", "[1, 100000]"),
    ("rdst", "peers", "max_shapelets", "100001", "[1, 100000]"),
    # the CNN
    ("cnn", "deep", "L", "0", "[1, inf)"),
    ("cnn", "deep", "max_epochs", "100001", "[1, 100000]"),
    ("cnn", "deep", "hidden_units", "16385", "[1, 16384]"),
    ("cnn", "deep", "channels", "[8, 8, 4097]", "a list of 3 items, each an int in the range [1, 4096]"),
    ("cnn", "deep", "channels", "[8, 8]", "a list of 3 items"),
    ("cnn", "deep", "validation_fraction", "1.0", "[0.0, 1.0)"),
    ("cnn", "deep", "patience", "0", "[1, inf)"),
    ("cnn", "deep", "learning_rate", "0", "(0.0, inf)"),
    ("cnn", "deep", "vote", "sof", "'hard', 'soft'"),
    ("cnn", "deep", "train_windows", "-1", "'all', 'first'"),
    ("cnn", "deep", "n_jobs", "-2", "{-1}"),
    # InceptionTime
    ("inception-time", "deep", "n_networks", "101", "[1, 100]"),
    ("inception-time", "deep", "depth", "0", "[1, 100]"),
    ("inception-time", "deep", "n_filters", "1025", "[1, 1024]"),
    ("inception-time", "deep", "kernel_size", "1001", "[1, 1000]"),
    ("inception-time", "deep", "bottleneck_size", "1025", "[1, 1024]"),
    ("inception-time", "deep", "max_epochs", "100001", "[1, 100000]"),
    ("inception-time", "deep", "lr_factor", "1.0", "(0.0, 1.0)"),
    ("inception-time", "deep", "lr_patience", "-1", "[0, inf)"),
    ("inception-time", "deep", "patience", "0", "[1, inf) or None"),
    # the tuned extra-trees, through its method
    ("touch-et-tuned", None, "n_estimators", "100001", "[1, 100000]"),
    ("touch-et-tuned", None, "n_estimators", "0", "[1, 100000]"),
    ("touch-et-tuned", None, "inner_folds", "1", "[2, 1000]"),
    ("touch-et-tuned", None, "inner_folds", "1001", "[2, 1000]"),
    ("touch-et-tuned", None, "grid_keep", "[null, 0]", "a non-empty list, each None or an int"),
    ("touch-et-tuned", None, "grid_max_features", "[]", "a non-empty list"),
    ("touch-et-tuned", None, "max_groups_loo", "-1", "[0, inf)"),
    # the wrappers, through the methods that use them
    ("touch-select", None, "inner_folds", "1", "None or an int in the range [2, 1000]"),
    ("touch-select", None, "inner_folds", "1001", "None or an int in the range [2, 1000]"),
    ("touch-rocket-fusion", "peers", "inner_folds", "1000000000000000000", "[2, 1000]"),
    ("touch-rocket-fusion", "peers", "weights", "[]", "None or a non-empty list"),
    ("touch-et-adapt", None, "sd_floor", "0", "(0.0, inf)"),
    ("touch-et-adapt", None, "sd_floor", ".inf", "(0.0, inf)"),
    ("touch-et-adapt", None, "scale", "1", "must be an instance of 'bool'"),
    ("touch-et-shift", None, "copies", "101", "[0, 100]"),
    ("touch-et-shift", None, "copies", "-1", "[0, 100]"),
    ("touch-et-shift", None, "gain", "[0, 1]", "(0.0, inf), low <= high"),
    ("touch-et-shift", None, "gain", "[1.2, 0.8]", "low <= high"),
    ("touch-et-shift", None, "offset", "[0, 1.5]", "[-1.0, 1.0], low <= high"),
    ("touch-et-shift", None, "noise", "[-0.5, 0]", "[0.0, inf), low <= high"),
    ("touch-et-shift", None, "ar_coef", "[0, 1]", "[0.0, 1.0), low <= high"),
    ("touch-et-shift", None, "dead", "[0, 1.5]", "[0.0, 1.0], low <= high"),
    ("touch-et-shift", None, "ar_share", "1.5", "[0.0, 1.0]"),
    ("touch-et-shift", None, "crop", "0", "(0.0, 1.0]"),
    ("touch-et-quiet", None, "gate_c", "0", "(0.0, inf)"),
    ("touch-et-quiet", None, "quiet_frames", "1.0", "[0.0, 1.0)"),
    ("touch-et-quiet", None, "stride", "0", "(0.0, 1.0]"),
    ("touch-et-quiet", None, "sure", "1.5", "(0.0, 1.0]"),
    ("touch-live", None, "detector_params", "[1]", "dict"),
    ("touch-live", None, "idle", "3", "str"),
]


@pytest.mark.parametrize("entry,field,value,bound", [
    pytest.param(e, f, v, b, marks=_needs(x), id=f"{e}-{f}-{v}") for e, x, f, v, b in BEYOND])
def test_a_value_beyond_a_bound_is_refused_at_its_field_naming_the_bound(entry, field, value, bound):
    out = _refusal(entry, f"{{{field}: {value}}}")
    assert f"p.yaml:7: methods[0].params.{field}: " in out, out
    assert "parameter of " in out and bound in out, out


#: (entry, optional extra, every parameter at its bound, accepted together)
AT_BOUND = [
    ("minirocket", "peers", "{n_kernels: 84, max_dilations_per_kernel: 1, n_jobs: -1, length: 1}"),
    ("minirocket", "peers", "{n_kernels: 100000, n_jobs: 1, length: null}"),
    ("multirocket", "peers", "{n_kernels: 84}"),
    ("multirocket-hydra", "peers,deep", "{n_kernels: 128, n_groups: 1024}"),
    ("multirocket-hydra", "peers,deep", "{n_kernels: 1, n_groups: 1}"),
    ("quant", "peers,deep", "{interval_depth: 16, quantile_divisor: 1}"),
    ("quant", "peers,deep", "{interval_depth: 1}"),
    ("rdst", "peers", "{max_shapelets: 100000}"),
    ("rdst", "peers", "{max_shapelets: 1}"),
    ("cnn", "deep", "{L: 1, max_epochs: 100000, hidden_units: 16384, channels: [1, 1, 4096], "
                    "validation_fraction: 0.0, patience: 1, vote: hard, train_windows: [0], test_windows: all, "
                    "n_jobs: -1, weight_decay: 0.0, validation_by: rows, scaling: none}"),
    ("cnn", "deep", "{max_epochs: 1, hidden_units: 1, validation_fraction: null, train_windows: 0}"),
    ("inception-time", "deep", "{n_networks: 100, depth: 100, n_filters: 1024, kernel_size: 1000, "
                               "bottleneck_size: 1024, max_epochs: 100000, lr_patience: 0, min_lr: 0.0, "
                               "patience: null, validation_fraction: 0.0, use_residual: false}"),
    ("inception-time", "deep", "{n_networks: 1, depth: 1, n_filters: 1, kernel_size: 1, bottleneck_size: 1, "
                               "max_epochs: 1, patience: 1}"),
    ("touch-et-tuned", None, "{n_estimators: 100000, inner_folds: 1000, grid_keep: [null, 1], "
                                      "grid_max_features: [1.0], max_groups_loo: 0}"),
    ("touch-et-tuned", None, "{n_estimators: 1, inner_folds: 2}"),
    ("touch-select", None, "{inner_folds: 2}"),
    ("touch-select", None, "{inner_folds: 1000}"),
    ("touch-rocket-fusion", "peers", "{inner_folds: 1000, weights: [[1, 0]]}"),
    ("touch-et-adapt", None, "{sd_floor: 0.000001, scale: true, params: {n_estimators: 100000}}"),
    ("touch-et-shift", None, "{copies: 100, gain: [0.5, 0.5], offset: [-1, 1], noise: [0, 0], ar_coef: [0, 0.99], "
                             "dead: [0, 1], ar_share: 1, crop: 1}"),
    ("touch-et-shift", None, "{copies: 0, ar_share: 0}"),
    ("touch-et-quiet", None, "{gate_c: 0.000001, quiet_frames: 0.0, stride: 1, sure: 1, gate: false}"),
    ("touch-live", None, "{detector_params: {n_estimators: 100000}, idle: null}"),
]


@pytest.mark.parametrize("entry,params", [
    pytest.param(e, p, marks=_needs(x), id=f"{e}-{i}") for i, (e, x, p) in enumerate(AT_BOUND)])
def test_the_values_at_the_bounds_are_accepted(entry, params):
    assert _refusal(entry, params) == ""


@pytest.mark.parametrize("entry,params,field,bound", [
    # a wrapper's inner estimator: its own declared domain, at the nested field
    ("touch-et-shift", "{params: {n_estimators: 100001}}", "params.n_estimators", "[1, 100000]"),
    ("touch-et-quiet", "{params: {keep: 0}}", "params.keep", "None or an int in the range [1, inf)"),
    ("touch-et-adapt", "{params: {max_features: sqr}}", "params.max_features", "'log2', 'sqrt'"),
    ("touch-live", "{detector_params: {n_estimators: 0}}", "detector_params.n_estimators", "[1, 100000]"),
])
def test_an_inner_estimators_domain_is_reached_through_its_wrapper(entry, params, field, bound):
    out = _refusal(entry, params)
    assert f"p.yaml:7: methods[0].params.{field}: " in out and bound in out, out


def test_a_classifier_entry_reaches_the_same_domains():
    out = _refusal("touch-extra-trees-tuned", "{inner_folds: 1001}", section="classifiers")
    assert "p.yaml:8: classifiers[0].params.inner_folds: " in out and "[2, 1000]" in out, out
    assert _refusal("touch-extra-trees-tuned", "{inner_folds: 1000}", section="classifiers") == ""
