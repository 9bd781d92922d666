"""A protocol's scheme is built once per repetition and shared by every layer that asks it something
(the checks, the data preparation, the folds, the task plan and the leakage label); its parameters are
validated once, when the protocol is read, and every build takes the validated model."""

from __future__ import annotations

from touchbench.engine import run_protocol
from touchbench.protocols.schemes import SPLITTERS, Splitter


def _counting(monkeypatch) -> list[tuple]:
    built: list[tuple] = []
    real = Splitter.__dict__["from_params"].__func__

    def counted(cls, params, target="gesture", random_state=None):
        built.append((cls.name, random_state))
        return real(cls, params, target=target, random_state=random_state)

    monkeypatch.setattr(Splitter, "from_params", classmethod(counted))
    return built


def test_a_run_builds_its_scheme_once_per_repetition(tmp_path, monkeypatch):
    built = _counting(monkeypatch)
    p = tmp_path / "twice.yaml"
    p.write_text("name: twice\ndataset: scene:tiny\nscheme: {name: kfold, k: 3}\nrepetitions: 2\n"
                 "features: [[sd]]\nclassifiers: [{name: gaus-rf, params: {n_estimators: 5}}]\n")
    run_protocol(p, out=tmp_path / "results", progress=False, jobs=1)
    assert len(built) == 2  # one scheme per repetition: two repetitions
    assert len({seed for _, seed in built}) == 2  # each its own seed


def test_a_copy_with_another_seed_builds_its_own(tmp_path):
    from touchbench.protocols.loading import parse_protocol

    p = parse_protocol("name: s\ndataset: scene:tiny\nscheme: loso\nfeatures: [[sd]]\n"
                       "classifiers: [gaus-rf]\n")
    assert p.splitter(0) is p.splitter(0)
    assert p.splitter(1) is not p.splitter(0)
    other = p.model_copy(update={"seed": 7})
    assert other.splitter(0) is not p.splitter(0)
    assert other.splitter(0).random_state != p.splitter(0).random_state


STREAM = """\
name: live-once
dataset: haart-sample
scheme:
  name: stream
  base: loso
  idle: notouch
  gap_s: [0.5, 1.5]
  per_stream: 1
  hop_s: 0.2
  rules: [{name: hmm, switch: 0.01}]
methods: [touch-et-fast]
repetitions: 2
"""


def test_a_stream_protocols_scheme_parameters_are_validated_once_per_read_and_run(tmp_path, monkeypatch):
    validated: dict[str, list[dict]] = {"stream": [], "loso": []}
    for name in validated:
        params = SPLITTERS.get(name).Params

        def counted(cls, obj, *args, real=params.model_validate, seen=validated[name], **kw):
            seen.append(obj)
            return real(obj, *args, **kw)

        monkeypatch.setattr(params, "model_validate", classmethod(counted))
    built = _counting(monkeypatch)
    p = tmp_path / "live.yaml"
    p.write_text(STREAM)
    run_protocol(p, out=tmp_path / "results", progress=False, jobs=1)
    # worked out by hand: reading the protocol validates the scheme's parameters and those of the
    # scheme it wraps (the checks: 1 each); the run builds one scheme per repetition (2), each with
    # its base (2), from those models, and the data preparation, the folds, the plan and the leakage
    # label ask the built ones: 1 validation of each in all
    assert [len(v) for v in validated.values()] == [1, 1]
    assert validated["stream"][0]["rules"] == [{"name": "hmm", "switch": 0.01}]
    assert sorted(name for name, _ in built) == ["loso", "loso", "stream", "stream"]


def test_a_scheme_is_not_built_from_another_schemes_parameters():
    import pytest

    loso = SPLITTERS.get("loso").Params.model_validate({})
    with pytest.raises(TypeError, match="kfold"):
        SPLITTERS.get("kfold").from_params(loso)
