"""A protocol's scheme is built once per repetition and shared by every layer that asks it something
(the checks, the data preparation, the folds, the task plan and the leakage label)."""

from __future__ import annotations

import touchbench.protocols.schema as schema
from touchbench.engine import run_protocol


def _counting(monkeypatch) -> list[tuple]:
    built: list[tuple] = []
    real = schema.make_splitter

    def counted(name, **kw):
        built.append((name, kw["random_state"]))
        return real(name, **kw)

    monkeypatch.setattr(schema, "make_splitter", counted)
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
