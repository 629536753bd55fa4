"""robodiff.warmup: builds into a fresh cache through robodiff-worker processes, then a
local-mode Client (no server) finds the functions compiled; progress, errors, the GIL."""

import json
import threading

import numpy as np
import pytest

import robodiff
from conftest import ARM7, SPECS

BUILT_SPECS = [SPECS / "crba.json", SPECS / "nle.json"]


@pytest.fixture(scope="module")
def warmed(tmp_path_factory):
    """One warmup of arm7's CRBA and NLE into a new cache, recording progress calls and
    how often a Python thread ran meanwhile (it cannot while the GIL is held)."""
    cache_dir = tmp_path_factory.mktemp("warmup") / "cache"
    calls = []
    ticks = [0]
    done = threading.Event()

    def count():
        while not done.is_set():
            ticks[0] += 1
            done.wait(0.001)

    counter = threading.Thread(target=count)
    counter.start()
    try:
        summary = robodiff.warmup(ARM7, BUILT_SPECS, cache_dir=cache_dir, progress=calls.append, jobs=2)
    finally:
        done.set()
        counter.join()
    return cache_dir, summary, calls, ticks[0]


def test_warmup_builds_each_spec_and_reports_it(warmed):
    _, summary, _, _ = warmed
    assert summary.ok and not summary.failed and not summary.cached
    assert [r.spec for r in summary.results] == [str(p) for p in BUILT_SPECS]
    assert [r.function for r in summary.built] == ["crba", "nle"]
    for result in summary.results:
        assert result.state == "done" and result.robot == "arm7" and result.urdf == str(ARM7)
        assert len(result.key) == 64 and result.library_bytes > 0 and result.seconds > 0
    assert summary.seconds >= max(r.seconds for r in summary.results)


def test_progress_is_called_once_per_spec_with_its_final_result(warmed):
    _, summary, calls, _ = warmed
    assert len(calls) == len(BUILT_SPECS)
    assert sorted(calls, key=lambda r: r.spec) == sorted(summary.results, key=lambda r: r.spec)


def test_the_gil_is_released_while_building(warmed):
    _, summary, _, ticks = warmed
    # The thread ticks about once a millisecond; the builds take seconds.
    assert ticks > 100 * summary.seconds, f"{ticks} ticks in {summary.seconds:.1f} s"


def test_a_local_client_then_finds_the_functions_compiled(warmed):
    cache_dir, summary, _, _ = warmed
    arm7 = robodiff.Client("local", cache_dir=cache_dir).load(ARM7)
    crba = arm7.function(SPECS / "crba.json")
    assert crba.mode == "local"
    q = np.linspace(-1.0, 1.0, 7)
    mass = crba(q=q)["value"]
    np.testing.assert_allclose(mass, mass.T, atol=1e-12)  # the joint-space inertia matrix
    assert np.all(np.linalg.eigvalsh(mass) > 0)
    keys = {entry.key for entry in robodiff.cache.ls(cache_dir)}
    assert keys == {r.key for r in summary.results}


def test_a_second_warmup_finds_everything_cached(warmed):
    cache_dir, first, _, _ = warmed
    calls = []
    again = robodiff.warmup([ARM7], BUILT_SPECS, cache_dir=cache_dir, progress=calls.append)
    assert [r.state for r in again.results] == ["cached", "cached"]
    assert [r.key for r in again.results] == [r.key for r in first.results]
    assert len(calls) == 2


def test_a_spec_that_does_not_parse_is_refused_before_building(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"function": "rnea", "outputs": [{"kind": "jacobain"}]}))
    with pytest.raises(robodiff.Error) as raised:
        robodiff.warmup(ARM7, [SPECS / "crba.json", bad], cache_dir=tmp_path / "cache")
    assert raised.value.code == "INVALID_ARGUMENT"
    assert "bad.json" in raised.value.message and "jacobain" in raised.value.message
    assert robodiff.cache.ls(tmp_path / "cache") == []  # nothing was built


def test_missing_files_are_named(tmp_path):
    with pytest.raises(robodiff.Error, match=r"INVALID_ARGUMENT: urdf .*missing\.urdf: no such file"):
        robodiff.warmup(tmp_path / "missing.urdf", SPECS / "crba.json", cache_dir=tmp_path / "cache")
    with pytest.raises(robodiff.Error, match=r"spec .*nope\.json: no such file"):
        robodiff.warmup(ARM7, [tmp_path / "nope.json"], cache_dir=tmp_path / "cache")


def test_a_robot_that_does_not_load_is_a_failed_result(tmp_path):
    broken = tmp_path / "broken.urdf"
    broken.write_text("<robot name='broken'><link name='a'/><joint name='j' type='revolute'></joint></robot>")
    summary = robodiff.warmup(broken, SPECS / "crba.json", cache_dir=tmp_path / "cache")
    assert not summary.ok
    [failed] = summary.failed
    assert failed.state == "failed" and failed.message


def test_wrong_arguments_raise(tmp_path):
    with pytest.raises(TypeError, match="spec files' paths"):
        robodiff.warmup(ARM7, {"function": "crba"}, cache_dir=tmp_path)
    with pytest.raises(TypeError, match="progress must be callable"):
        robodiff.warmup(ARM7, SPECS / "crba.json", cache_dir=tmp_path, progress=3)
    with pytest.raises(ValueError, match="jobs must be between 1 and 256"):
        robodiff.warmup(ARM7, SPECS / "crba.json", cache_dir=tmp_path, jobs=0)


def test_an_exception_in_progress_is_raised_after_the_warmup(warmed):
    cache_dir, _, _, _ = warmed
    seen = []

    def fail(result):
        seen.append(result)
        raise RuntimeError("stop here")

    with pytest.raises(RuntimeError, match="stop here"):
        robodiff.warmup(ARM7, BUILT_SPECS, cache_dir=cache_dir, progress=fail)
    assert len(seen) == 1  # not called again after it raised
