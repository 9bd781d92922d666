"""Real HAART (../shared/data/haart) and the raw reader's quirks and bad input.

Expected values are computed here from the README's description with plain
Python (gzip + str.split), not by the reader under test.
"""

from __future__ import annotations

import gzip
import hashlib
import multiprocessing as mp
from pathlib import Path

import numpy as np
import pytest

from touchbench.catalog import load_dataset
from touchbench.datasets.haart import build_haart, find_recordings
from touchbench.core.errors import DataError

from helpers import SUBPROCESS_HANG_S, random_recording, write_recording

# The ten placeholders as the data README lists them (by hand, not by code).
README_PLACEHOLDERS = {f"s05-foam-none-{g}" for g in ("constant", "notouch", "pat", "rub", "scratch", "stroke", "tickle")} | {
    "s03-foam-none-rub", "s06-foam-none-rub", "s02-none-fur-constant"}


def _lines(path: Path) -> list[list[int]]:
    data = gzip.open(path, "rt").read() if path.suffix == ".gz" else path.read_text()
    return [[int(v) for v in line.split(",")] for line in data.splitlines() if line.strip()]


def _raw_file(d: Path, participant: int, stem: str) -> Path:
    folder = d / "raw" / f"140729-{participant}"
    return next(p for p in folder.iterdir() if p.name.startswith(f"140729-{participant}{stem}"))


@pytest.mark.realdata
def test_haart_counts_and_placeholders(real_haart):
    ds = real_haart
    assert len(ds) == 830
    assert ds.meta["subject"].nunique() == 10
    assert sorted(ds.meta["gesture"].unique()) == ["constant", "notouch", "pat", "rub", "scratch", "stroke", "tickle"]
    assert all(c.shape == (432, 8, 8) and c.dtype == np.uint16 for c in ds.captures)
    found = {p["capture_id"] for p in ds.provenance["placeholders"]}
    assert found == README_PLACEHOLDERS
    assert not set(ds.meta["capture_id"]) & README_PLACEHOLDERS
    assert ds.meta["split"].value_counts().to_dict() == {"train": 578, "test": 250, "none": 2}
    none = set(ds.meta.loc[ds.meta["split"] == "none", "capture_id"])
    assert none == {"s10-curve-fur-constant", "s09-none-fur-constant"}


@pytest.mark.realdata
def test_haart_corrected_window_values(real_haart, real_haart_dir):
    # middle 8 s = frames 55..486 (1-based) -> lines 541.. (1-based); inner 8 x 8; 1023 - raw
    lines = _lines(_raw_file(real_haart_dir, 7, "nonelongscratch"))
    cap = real_haart.captures[list(real_haart.meta["capture_id"]).index("s07-none-long-scratch")]
    for f in (0, 1, 200, 431):
        frame = lines[(54 + f) * 10:(55 + f) * 10]
        expect = [[1023 - frame[r][c] for c in range(1, 9)] for r in range(1, 9)]
        assert cap[f].tolist() == expect


@pytest.mark.realdata
@pytest.mark.parametrize("participant, stem, n_lines", [(3, "curveshortpat", 10800), (7, "nonelongscratch", 8100), (7, "nonefurrub", 7780)])
def test_longer_files_use_first_5400_lines(real_haart, real_haart_dir, participant, stem, n_lines):
    # the README's three long files: frames past 540 must never be read
    lines = _lines(_raw_file(real_haart_dir, participant, stem))
    assert len(lines) == n_lines
    row = real_haart.meta[(real_haart.meta["subject"] == f"s{participant:02d}") & (real_haart.meta["source"].str.endswith(stem + ".csv"))]
    assert len(row) == 1
    cap = real_haart.captures[row.index[0]]
    last = lines[485 * 10:486 * 10]
    assert cap[431].tolist() == [[1023 - last[r][c] for c in range(1, 9)] for r in range(1, 9)]


@pytest.mark.realdata
def test_participant_1_files_without_csv_suffix(real_haart, real_haart_dir):
    names = [p.name for p in (real_haart_dir / "raw" / "140729-1").iterdir()]
    assert all(not n.endswith(".csv.gz") for n in names if n != "note.txt")
    assert (real_haart.meta["subject"] == "s01").sum() == 84


@pytest.mark.realdata
def test_haart_challenge_split_and_window(real_haart_challenge, real_haart_dir):
    ds = real_haart_challenge
    assert ds.meta["split"].value_counts().to_dict() == {"train": 578, "test": 251}
    ids = set(ds.meta["capture_id"])
    assert "s02-none-fur-constant" in ids  # the copy the released test file holds
    assert "s09-none-fur-constant" not in ids and "s10-curve-fur-constant" not in ids
    assert not {f"s05-foam-none-{g}" for g in ("pat", "rub")} & ids
    train_subjects = set(ds.meta.loc[ds.meta["split"] == "train", "subject"])
    assert train_subjects == {"s04", "s08", "s07", "s05", "s10", "s03", "s06"}
    assert list(dict.fromkeys(ds.meta["challenge_label"])) == ["P4", "P8", "P7", "P5", "P10", "P3", "P6", "T1", "T9", "T2"]
    # README steps 1-4, literally: trimmed stream of 8-value lines, frame i from line 8 i + 55 (1-based)
    lines = _lines(_raw_file(real_haart_dir, 4, "foamfurtickle"))[:5400]
    trimmed = [[1023 - v for v in line[1:9]] for i, line in enumerate(lines, start=1) if i % 10 not in (0, 1)]
    cap = ds.captures[list(ds.meta["capture_id"]).index("s04-foam-fur-tickle")]
    for f in (0, 5, 431):
        assert cap[f].tolist() == trimmed[8 * f + 54:8 * f + 62]
    # the bug as the README states it: rows = lines 7-8 of frame i+7 then lines 1-6 of frame i+8 (1-based)
    full = np.array(trimmed).reshape(540, 8, 8)
    np.testing.assert_array_equal(cap[10], np.concatenate([full[10 + 6, 6:8], full[10 + 7, 0:6]]))


# ---------------------------------------------------------------- synthetic
def _folder(tmp_path: Path, files: dict[str, list[str]], notes: dict[int, str] | None = None, gz=False) -> Path:
    raw = tmp_path / "haart" / "raw"
    for name, lines in files.items():
        participant = name.split("-")[1].split("c")[0].split("f")[0].split("n")[0]
        folder = raw / f"140729-{participant}"
        folder.mkdir(parents=True, exist_ok=True)
        write_recording(folder / name, lines, gz=gz)
    for p, text in (notes or {}).items():
        (raw / f"140729-{p}" / "note.txt").write_text(text)
    return tmp_path / "haart"


def test_plain_and_gzipped_give_the_same_dataset(tmp_path):
    files = {"140729-1nonenonepat.csv": random_recording(1), "140729-1nonenonerub.csv": random_recording(2)}
    a = build_haart(_folder(tmp_path / "a", files) / "raw")
    b = build_haart(_folder(tmp_path / "b", files, gz=True) / "raw")
    assert a.content_hash == b.content_hash and len(a) == 2


def test_placeholders_found_by_content_with_and_without_notes(tmp_path):
    same = random_recording(7)
    files = {
        "140729-1nonenonenotouch.csv": same,
        "140729-1nonenonerub.csv": same,  # no note: the notouch one is kept
        "140729-2foamshortpat.csv": random_recording(8),
        "140729-2foamnonepat.csv": random_recording(8),  # note: ALL foamnone are foamshort
        "140729-2foamnonerub.csv": random_recording(9),
    }
    ds = build_haart(_folder(tmp_path, files, notes={2: "ALL foamnone are foamshort"}) / "raw")
    ph = {p["capture_id"]: p for p in ds.provenance["placeholders"]}
    assert set(ph) == {"s01-none-none-rub", "s02-foam-none-pat"}
    assert ph["s01-none-none-rub"]["copy_of"] == "s01-none-none-notouch"
    assert "note.txt" in ph["s02-foam-none-pat"]["reason"]
    assert "s02-foam-none-rub" in set(ds.meta["capture_id"])  # named by the note but not a copy: kept


@pytest.mark.parametrize(
    "mutate, message, line",
    [
        (lambda L: L[:4000], "truncated recording", 4001),
        (lambda L: L[:10] + ["1,2,3,x,5,6,7,8,9,10"] + L[11:], "not an integer value: 'x'", 11),
        (lambda L: L[:20] + ["1,2,3,4,5,6,7,8,9"] + L[21:], "expected 10 comma-separated values, found 9", 21),
        (lambda L: L[:30] + ["1,2,3,4,5,6,7,8,9,10,11"] + L[31:], "found 11", 31),
        (lambda L: L[:40] + ["1,2,3,4,-5,6,7,8,9,10"] + L[41:], "out of the ADC range", 41),
        (lambda L: L[:50] + ["1,2,3,4,5,6,7,8,9,2000"] + L[51:], "out of the ADC range", 51),
        (lambda L: L[:60] + ["1,2,3,4,5,nan,7,8,9,10"] + L[61:], "not an integer value: 'nan'", 61),
    ],
)
def test_bad_recordings_name_file_and_line_and_leave_no_cache(tmp_path, mutate, message, line):
    files = {"140729-1nonenonepat.csv": random_recording(3), "140729-1nonenonerub.csv": mutate(random_recording(4))}
    d = _folder(tmp_path, files)
    cache = tmp_path / "cache"
    with pytest.raises(DataError) as e:
        load_dataset("haart", data_dir=d, cache_dir=cache)
    assert "140729-1nonenonerub.csv" in str(e.value) and message in str(e.value)
    assert e.value.line == line
    assert not cache.exists() or not any(cache.rglob("*.parquet")) and not any(cache.rglob("*.tmp"))


def test_blank_lines_are_skipped(tmp_path):
    lines = random_recording(4)
    a = build_haart(_folder(tmp_path / "a", {"140729-1nonenonerub.csv": lines}) / "raw")
    b = build_haart(_folder(tmp_path / "b", {"140729-1nonenonerub.csv": lines[:70] + [""] + lines[70:]}) / "raw")
    assert a.content_hash == b.content_hash


def test_missing_folder_is_one_clear_error(tmp_path):
    with pytest.raises(DataError, match="HAART raw folder not found"):
        load_dataset("haart", data_dir=tmp_path / "nowhere", cache_dir=tmp_path / "c")
    (tmp_path / "empty" / "raw").mkdir(parents=True)
    with pytest.raises(DataError, match="no HAART recordings"):
        load_dataset("haart", data_dir=tmp_path / "empty", cache_dir=tmp_path / "c")


def test_cache_is_used_and_keyed_by_content(tmp_path, monkeypatch):
    files = {"140729-1nonenonepat.csv": random_recording(5)}
    d = _folder(tmp_path, files)
    cache = tmp_path / "cache"
    first = load_dataset("haart", data_dir=d, cache_dir=cache)
    import touchbench.datasets.haart as haart

    monkeypatch.setattr(haart, "build_haart", lambda raw: (_ for _ in ()).throw(AssertionError("rebuilt")))
    again = load_dataset("haart", data_dir=d, cache_dir=cache)  # served from the cache
    assert again.content_hash == first.content_hash
    # an edited source file changes the key: rebuilt (and here, refused by the stub)
    write_recording(d / "raw" / "140729-1" / "140729-1nonenonepat.csv", random_recording(6))
    with pytest.raises(AssertionError, match="rebuilt"):
        load_dataset("haart", data_dir=d, cache_dir=cache)


def _load_at_once(data_dir: str, cache: str, barrier, out) -> None:
    barrier.wait(SUBPROCESS_HANG_S)
    out.put(load_dataset("haart", data_dir=data_dir, cache_dir=cache).content_hash)


def test_two_processes_filling_one_cache_at_once_both_get_the_whole_dataset(tmp_path):
    """Two runs (or two test workers) converting the same dataset into one cache folder at the same
    moment: both build it, each writes a whole file under a name of its own and renames it into place."""
    files = {f"140729-{p}nonenone{g}.csv": random_recording(p * 10 + i)
             for p in (1, 2) for i, g in enumerate(("pat", "rub", "stroke"))}
    d = _folder(tmp_path, files)
    cache = tmp_path / "cache"
    ctx = mp.get_context("fork")
    barrier, out = ctx.Barrier(2), ctx.Queue()
    procs = [ctx.Process(target=_load_at_once, args=(str(d), str(cache), barrier, out)) for _ in range(2)]
    for p in procs:
        p.start()
    hashes = [out.get(timeout=SUBPROCESS_HANG_S) for _ in procs]
    for p in procs:
        p.join(SUBPROCESS_HANG_S)
        assert p.exitcode == 0
    expected = load_dataset("haart", data_dir=d, cache_dir=tmp_path / "fresh").content_hash
    assert hashes == [expected, expected]
    assert len(list((cache / "datasets").glob("*.parquet"))) == 1
    assert not list((cache / "datasets").glob(".*.tmp"))  # no temporary file left behind
    assert load_dataset("haart", data_dir=d, cache_dir=cache).content_hash == expected


def test_recording_names_are_parsed(tmp_path):
    d = _folder(tmp_path, {"140729-10curvefurconstant.csv": random_recording(1)}, gz=True)
    (r,) = find_recordings(d / "raw")
    assert (r.participant, r.substrate, r.cover, r.gesture, r.subject) == (10, "curve", "fur", "constant", "s10")


def _damage_frames(path: Path) -> None:
    """Change one value of the cached frames, keeping the file readable and its saved hash."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    t = pq.read_table(path)
    frames = t.column("frames").combine_chunks()
    values = frames.to_pylist()
    values[0] = bytes([255 - values[0][0]]) + values[0][1:]
    t = t.set_column(t.column_names.index("frames"), "frames", pa.array(values, type=frames.type))
    pq.write_table(t.replace_schema_metadata(t.schema.metadata), path)


def test_a_damaged_or_cut_cache_entry_is_rebuilt_from_the_raw_files(tmp_path, caplog):
    import warnings

    d = _folder(tmp_path, {"140729-1nonenonepat.csv": random_recording(5)})
    cache = tmp_path / "cache"
    first = load_dataset("haart", data_dir=d, cache_dir=cache)
    (entry,) = (cache / "datasets").glob("haart-*.parquet")
    for damage in (_damage_frames, lambda p: p.write_bytes(p.read_bytes()[: len(p.read_bytes()) // 2])):
        damage(entry)
        caplog.clear()
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # not "new data"
            again = load_dataset("haart", data_dir=d, cache_dir=cache)
        assert again.content_hash == first.content_hash
        assert "the cached copy of haart is damaged" in caplog.text and "rebuilt from its source files" in caplog.text
        caplog.clear()
        assert load_dataset("haart", data_dir=d, cache_dir=cache).content_hash == first.content_hash
        assert "damaged" not in caplog.text  # the rebuilt entry is whole again


def test_missing_data_names_where_touchbench_looked_never_the_install_location(tmp_path, monkeypatch):
    """As from an installed wheel: the package inside a virtual environment's site-packages, run from a
    folder without the data; the message names the folders searched and how to point touchbench at the data."""
    import touchbench.core.paths as paths

    site = tmp_path / "venv" / "lib" / "python3.11" / "site-packages"
    (site / "touchbench").mkdir(parents=True)
    monkeypatch.setattr(paths, "REPO_ROOT", site)
    monkeypatch.delenv("TOUCHBENCH_DATA_DIR", raising=False)
    (tmp_path / "work").mkdir()
    monkeypatch.chdir(tmp_path / "work")
    with pytest.raises(DataError) as e:
        load_dataset("haart", cache_dir=tmp_path / "c")
    msg = str(e.value)
    assert "venv" not in msg  # nothing computed from where the package is installed
    assert f"looked for the haart data in {tmp_path / 'shared' / 'data' / 'haart'}, " in msg
    assert str(tmp_path / "work" / "shared" / "data" / "haart") in msg
    assert "(TOUCHBENCH_DATA_DIR is not set); set TOUCHBENCH_DATA_DIR to the folder that holds haart/" in msg
    monkeypatch.setenv("TOUCHBENCH_DATA_DIR", str(tmp_path / "nowhere"))
    with pytest.raises(DataError, match=r"looked for the haart data in .*nowhere/haart \(TOUCHBENCH_DATA_DIR="):
        load_dataset("haart", cache_dir=tmp_path / "c")


def test_a_recording_that_does_not_match_sha256sums_is_refused(tmp_path):
    raw = tmp_path / "raw" / "140729-1"
    raw.mkdir(parents=True)
    lines = random_recording(3)
    write_recording(raw / "140729-1foamfurpat", lines, gz=True)
    good = hashlib.sha256(("\n".join(lines) + "\n").encode()).hexdigest()
    (tmp_path / "SHA256SUMS").write_text(f"{good}  ./140729-1/140729-1foamfurpat\n")
    assert len(build_haart(tmp_path / "raw")) == 1
    (tmp_path / "SHA256SUMS").write_text(f"{'0' * 64}  ./140729-1/140729-1foamfurpat\n")
    with pytest.raises(DataError, match="140729-1foamfurpat.gz: content does not match SHA256SUMS"):
        build_haart(tmp_path / "raw")
