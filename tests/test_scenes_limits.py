"""A scene too large for memory, or whose numbers overflow, is refused before anything is made,
naming the field and its line; a long generation stops on SIGTERM (touchbench.scenes.size,
touchbench.scenes.loading, touchbench.scenes.generate)."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from click.testing import CliRunner
from helpers import SUBPROCESS_HANG_S

import touchbench.scenes.size as size_module
from touchbench.core.errors import DataError
from touchbench.cli.main import cli
from touchbench.core.memory import available_memory, memory_limit
from touchbench.scenes import generate_scene, load_scene
from touchbench.scenes.generate import generate

# the tiny scene, its lines numbered by hand
SCENE = """\
name: small
description: four people, four gestures
seed: 1
effects: [style, baseline, noise]
sensor:
  grid: [8, 8]
  pitch_mm: 25.4
  frame_rate: 54
  value_range: [0, 1023]
  dtype: uint16
  gain: 60
  noise_sd: 0.8
  baseline: {level: 2.0, spread: 0.5, drift: 0.2}
population:
  subjects: 4
  style: {sd: 0.5, angle_deg: 30, location_mm: 30}
gestures:
  pat: {}
  rub: {force_n: 7, osc_hz: 2.0, osc_mm: 30}
  scratch: {osc_hz: 4.0, osc_mm: 15}
  stroke: {travel_mm: 150}
protocol:
  repetitions: 2
  segmentation:
    mode: fixed
    frames: 108
"""
# line 6 grid, 9 value_range, 11 gain, 12 noise_sd, 15 subjects, 19 rub, 23 repetitions, 26 frames

# 4 subjects x 2 repetitions x 4 gestures x 108 frames x 8 x 8 cells x 2 bytes, and 1024 bytes for each
# of the 32 captures' row, metadata and array
SMALL_BYTES = 4 * 2 * 4 * 108 * 8 * 8 * 2 + 32 * 1024  # 475,136


def scene_file(tmp_path: Path, old: str | None = None, new: str | None = None) -> Path:
    path = tmp_path / "small.yaml"
    text = SCENE if old is None else SCENE.replace(old, new)
    assert old is None or text != SCENE
    path.write_text(text)
    return path


def refusal(tmp_path: Path, old: str, new: str) -> str:
    """The error that loading the scene with ``old`` replaced by ``new`` gives, its folder left out."""
    path = scene_file(tmp_path, old, new)
    with pytest.raises(DataError) as e:
        load_scene(path)
    return str(e.value).replace(f"{tmp_path}/", "")


@pytest.mark.parametrize("old,new,field,line", [
    ("repetitions: 2", "repetitions: 1000000000", "protocol.repetitions", 23),
    ("subjects: 4", "subjects: 1000000000", "population.subjects", 15),
    ("frames: 108", "frames: 1000000000", "protocol.segmentation.frames", 26),
    ("grid: [8, 8]", "grid: [100000, 100000]", "sensor.grid", 6),
])
def test_a_scene_too_large_for_memory_is_refused_naming_the_field_and_line(tmp_path, old, new, field, line):
    message = refusal(tmp_path, old, new)
    assert message.startswith(f"small.yaml:{line}: invalid scene: {field}: the scene would make ")
    assert "a quarter of the memory available" in message and f"make {field} smaller" in message


def test_an_override_that_makes_a_scene_too_large_is_named_as_an_override(tmp_path):
    with pytest.raises(DataError, match=r"small\.yaml: invalid scene: protocol\.repetitions: .*"
                                        r"\(the value given as an override\)$"):
        load_scene(scene_file(tmp_path), repetitions=10**9)


def test_the_limit_is_the_bytes_of_the_captures_counted_by_hand(tmp_path, monkeypatch):
    spec = load_scene(scene_file(tmp_path))
    assert size_module.scene_size(spec).bytes == SMALL_BYTES
    # a limit one byte short refuses the scene before a capture is made; at the limit it is made
    monkeypatch.setattr(size_module, "memory_limit", lambda: SMALL_BYTES - 1)
    made = []
    monkeypatch.setattr(sys.modules["touchbench.scenes.generate"], "make_people", lambda *a: made.append(1))
    with pytest.raises(DataError, match=r"small\.yaml: invalid scene: protocol\.segmentation\.frames: .*475,136"):
        generate(spec, source=tmp_path / "small.yaml")
    assert made == []
    monkeypatch.undo()
    monkeypatch.setattr(size_module, "memory_limit", lambda: SMALL_BYTES)
    assert len(generate(spec)) == 32


def test_contact_segmentation_counts_each_gestures_nominal_length(tmp_path):
    # pat 2 s, rub 3 s, scratch 2 s, stroke 2 s; pad 0.5 s either side: 3 + 4 + 3 + 3 = 13 s of
    # frames at 54 Hz = 702 frames per person and repetition
    text = SCENE.replace("    mode: fixed\n    frames: 108\n", "    mode: contact\n    pad_s: 0.5\n")
    for old, new in [("pat: {}", "pat: {duration_s: 2}"), ("rub: {", "rub: {duration_s: 3, "),
                     ("scratch: {", "scratch: {duration_s: 2, "), ("stroke: {", "stroke: {duration_s: 2, ")]:
        text = text.replace(old, new)
    path = tmp_path / "contact.yaml"
    path.write_text(text)
    size = size_module.scene_size(load_scene(path))
    assert size.frames == 702 and size.bytes == 4 * 2 * 702 * 64 * 2 + 32 * 1024


@pytest.mark.parametrize("old,new,field,line", [
    ("gain: 60", "gain: 1.0e308", "gain", 11),
    ("gain: 60", "gain: .inf", "sensor.gain", 11),
    ("noise_sd: 0.8", "noise_sd: .nan", "sensor.noise_sd", 12),
    ("value_range: [0, 1023]", "value_range: [0, 100000]", "value_range", 9),
    ("rub: {force_n: 7,", "rub: {force_n: .inf,", "gestures.rub.force_n", 19),
])
def test_numbers_that_would_overflow_are_refused_at_validation(tmp_path, old, new, field, line):
    assert re.match(rf"small\.yaml:{line}: invalid scene: (\w+: )?{field}: ", refusal(tmp_path, old, new))


@pytest.mark.parametrize("written,fixed", [("1.0e300", "1.0e+300"), ("7e0", "7.0e+0"), ("-2E-3", "-2.0E-3")])
def test_a_number_yaml_reads_as_text_says_so_and_how_to_write_it(tmp_path, written, fixed):
    message = refusal(tmp_path, "rub: {force_n: 7,", f"rub: {{force_n: {written},")
    assert message == (f"small.yaml:19: invalid scene: gestures: gestures.rub.force_n: must be a number, got "
                       f"'{written}': YAML read '{written}' as a string, not a number: YAML 1.1 reads an exponent "
                       f"as a number only after a dot and with a sign; write {fixed.replace('E', 'e')}")


@pytest.mark.parametrize("seed", ["-1", "-1000000"])
def test_a_negative_seed_is_refused_naming_the_field(tmp_path, seed):
    message = refusal(tmp_path, "seed: 1", f"seed: {seed}")
    assert message.startswith("small.yaml:3: invalid scene: seed: ") and "greater than or equal to 0" in message
    r = CliRunner().invoke(cli, ["scenes", "generate", str(scene_file(tmp_path)), "--seed", "-1",
                                 "--out", str(tmp_path / "o.parquet")])
    assert r.exit_code == 2 and "Invalid value for '--seed'" in r.output and "Traceback" not in r.output


def test_counts_that_overflow_in_the_electronics_are_refused_before_writing(tmp_path):
    # a force of 1e300 N is finite, but no float32 reading of it is
    path = scene_file(tmp_path, "rub: {force_n: 7,", "rub: {force_n: 1.0e+300,")
    out = tmp_path / "out.parquet"
    r = CliRunner().invoke(cli, ["scenes", "generate", str(path), "--out", str(out)])
    assert r.exit_code == 3 and out.exists() is False
    assert f"{path}: capture " in r.output and "rub): the sensor's readings overflowed before the ADC" in r.output


def test_memory_limit_is_a_quarter_of_the_available_memory(monkeypatch):
    import touchbench.core.memory as memory

    monkeypatch.setattr(memory, "_meminfo_available", lambda: 8 * 2**30)
    monkeypatch.setattr(memory, "_cgroup_room", lambda: None)
    monkeypatch.setattr(memory, "_address_space_room", lambda: None)
    assert memory.memory_limit() == 2 * 2**30 and memory.memory_limit(2**20) == 2**20
    monkeypatch.setattr(memory, "_cgroup_room", lambda: 2 * 2**30)  # a container's limit below the machine's
    assert memory.available_memory() == 2 * 2**30 and memory.memory_limit() == 2**29
    monkeypatch.setattr(memory, "_meminfo_available", lambda: None)
    monkeypatch.setattr(memory, "_free_pages", lambda: None)
    monkeypatch.setattr(memory, "_cgroup_room", lambda: None)
    assert memory.available_memory() is None and memory.memory_limit() == memory.FALLBACK_BYTES


def test_an_address_space_limit_is_room_left_under_it(monkeypatch):
    import resource

    import touchbench.core.memory as memory

    monkeypatch.setattr(memory, "_meminfo_available", lambda: 64 * 2**30)
    monkeypatch.setattr(memory, "_cgroup_room", lambda: None)
    monkeypatch.setattr(resource, "getrlimit", lambda which: (6 * 2**30, resource.RLIM_INFINITY))
    monkeypatch.setattr(memory, "_virtual_size", lambda: 2 * 2**30)
    assert memory.available_memory() == 4 * 2**30 and memory.memory_limit() == 2**30  # (6 - 2) GiB / 4
    monkeypatch.setattr(memory, "_virtual_size", lambda: 7 * 2**30)  # already past it
    assert memory.available_memory() == 0
    monkeypatch.setattr(resource, "getrlimit", lambda which: (resource.RLIM_INFINITY, resource.RLIM_INFINITY))
    assert memory.available_memory() == 64 * 2**30


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="ulimit -v and /proc/self/status: Linux")
def test_a_scene_over_ulimit_v_is_refused_up_front(tmp_path):
    """Under `ulimit -v` (the process's virtual size plus 1 GiB) a scene of 6000 subjects, 6000 / 4
    times the small one's 475,136 bytes (about 680 MiB), is over a quarter of the room and refused
    when it is read, naming its field, rather than ending in a MemoryError while it is made."""
    path = scene_file(tmp_path, "subjects: 4", "subjects: 6000")
    code = (
        "import resource\n"
        "from touchbench.core.errors import DataError\n"
        "from touchbench.core.memory import _virtual_size\n"
        "from touchbench.scenes import load_scene\n"
        "resource.setrlimit(resource.RLIMIT_AS, (_virtual_size() + 2**30, resource.RLIM_INFINITY))\n"
        "try:\n"
        f"    load_scene({str(path)!r})\n"
        "    print('loaded')\n"
        "except DataError as e:\n"
        "    print(e)\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=SUBPROCESS_HANG_S,
                       env={**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parent.parent)})
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith(f"{path}:15: invalid scene: population.subjects: the scene would make 48,000 "
                               "captures"), r.stdout


def test_the_real_memory_is_read():
    assert available_memory() is None or 0 <= memory_limit() <= available_memory()


def _catches_sigterm(pid: int) -> bool:
    """Whether process ``pid`` has a SIGTERM handler (Linux: its status's SigCgt mask), or, where
    the system does not say, True."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return True
    mask = next(int(line.split()[1], 16) for line in status.splitlines() if line.startswith("SigCgt:"))
    return bool(mask >> (signal.SIGTERM - 1) & 1)


def test_a_long_generation_stops_on_sigterm_writing_nothing(tmp_path):
    # tiny with 1,000 repetitions: 16,000 captures, a minute of work or more; SIGTERM once the command
    # has its handler (then any moment will do: the generation must end, and say so)
    out = tmp_path / "big.parquet"
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parent.parent)}
    proc = subprocess.Popen([sys.executable, "-c", "from touchbench.cli.main import main; main()", "scenes",
                             "generate", "tiny", "--set", "protocol.repetitions=1000", "--out", str(out)],
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 60
        while proc.poll() is None and not _catches_sigterm(proc.pid) and time.monotonic() < deadline:
            time.sleep(0.05)
        time.sleep(1)
        proc.send_signal(signal.SIGTERM)
        deadline = time.monotonic() + 60
        while proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.2)
        assert proc.poll() is not None, "the generation went on after SIGTERM"
    finally:
        if proc.poll() is None:
            proc.kill()
        _, err = proc.communicate()
    assert proc.returncode == 130 and not out.exists(), err
    assert err.strip() == f"interrupted: nothing was written to {out}"


def test_generate_scene_names_the_scene_file_in_its_refusals(tmp_path):
    with pytest.raises(DataError, match=r"small\.yaml:23: invalid scene: protocol\.repetitions"):
        generate_scene(scene_file(tmp_path, "repetitions: 2", "repetitions: 1000000000"))
