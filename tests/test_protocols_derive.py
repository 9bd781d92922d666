"""Protocols made from protocols: a protocol's own data, read back, is the same protocol.

The audit's variants and the paper profiles change this data; if reading it back lost or changed
anything (a scheme parameter, an expected number, a design block), every derived protocol would
carry the loss. Checked here on every shipped protocol, against the protocol read from its file.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from touchbench.protocols.derive import derive, protocol_data
from touchbench.protocols.loading import load_protocol

SHIPPED = Path(__file__).resolve().parent.parent / "touchbench" / "protocols"
FILES = sorted(SHIPPED.glob("*.yaml")) + sorted((SHIPPED / "papers").glob("*.yaml"))


@pytest.mark.parametrize("path", FILES, ids=[p.name for p in FILES])
def test_a_protocol_read_back_from_its_data_is_the_same_protocol(path):
    original = load_protocol(path, deep=False)
    again = derive(original, protocol_data(original))
    assert again.content() == original.content()
    for block in ("expected", "design", "report", "audit", "description", "evaluations"):
        assert getattr(again, block) == getattr(original, block), block
    assert again.path == original.path  # relative dataset paths resolve from the same folder


def test_a_derived_protocol_says_how_it_was_made_and_validates_like_a_file(tmp_path):
    p = tmp_path / "p.yaml"
    p.write_text("name: p\ndataset: haart-sample\nscheme: {name: kfold, k: 5}\nfeatures: [[msd]]\n"
                 "classifiers: [gaus-rf]\n")
    original = load_protocol(p, deep=False)
    data = protocol_data(original)
    data["scheme"]["k"] = 3
    changed = derive(original, data, "# k capped\n")
    assert changed.text.startswith("# k capped\n") and changed.scheme.params == {"k": 3}
    data["scheme"]["k"] = 1
    with pytest.raises(Exception, match="k"):
        derive(original, data)
