"""Batch jobs through a real robodiffd (server_fixtures.py's process; DDS on the loopback
in a domain of this test's own, no iceoryx, its own cache), stopped by PID: a trajectory
job's every output against the same function called directly, listing, cancelling, and
the errors' codes."""

import json
import os

import numpy as np
import pytest

import robodiff
from conftest import ARM7, REPO, SPECS
from server_fixtures import (LOCK_TIMEOUT_S, RobodiffdProcess, RoudiLock, free_dds_domain,  # noqa: F401 (fixture)
                             loopback_dds, robodiffd_path)


def write_jobs_config(path, cache_dir, dds_domain, data_dirs):
    """robodiffd's config: its cache, DDS only (no RouDi needed), jobs reading data_dirs."""
    path.write_text(
        "[build]\nworkers = 1\n"
        f"[cache]\ndir = {json.dumps(str(cache_dir))}\n"
        f"[jobs]\ndata_dirs = {json.dumps(':'.join(str(d) for d in data_dirs))}\n"
        "[iceoryx]\nenabled = false\n"
        f"[dds]\ndomain = {dds_domain}\n"
        "[http]\nenabled = false\n"
        '[log]\nformat = "json"\n')


@pytest.fixture(scope="module")
def server_dir(tmp_path_factory):
    """robodiffd's folder: its config, cache and log, and the files jobs may read."""
    if not robodiffd_path().exists():
        pytest.skip(f"{robodiffd_path()} is not built (cmake --build build --target robodiffd)")
    return tmp_path_factory.mktemp("robodiffd-jobs")


@pytest.fixture(scope="module")
def job_client(server_dir, loopback_dds):  # noqa: F811 (the imported fixture)
    """A dds-mode Client of a robodiffd started for this module (/tmp/robodiff-roudi.lock
    held meanwhile, as for every test starting robodiffd)."""
    try:
        lock = RoudiLock(LOCK_TIMEOUT_S)
    except TimeoutError as error:
        pytest.skip(str(error))
    try:
        domain = free_dds_domain()
        config = server_dir / "robodiffd.conf"
        write_jobs_config(config, server_dir / "cache", domain, [REPO / "examples", server_dir])
        server = RobodiffdProcess(config, server_dir, domain)
        server.start()
        try:
            yield robodiff.Client(server.address("dds"), timeout=30.0)
        finally:
            server.terminate()
    finally:
        lock.release()


def write_trajectory(path, knots, seed):
    """A CSV trajectory of arm7 configurations (columns t, q_0 .. q_6); returns them."""
    q = np.random.default_rng(seed).uniform(-2.0, 2.0, size=(knots, 7))
    header = "t," + ",".join(f"q_{i}" for i in range(7))
    rows = [",".join([repr(0.01 * k)] + [repr(float(x)) for x in q[k]]) for k in range(knots)]
    path.write_text(header + "\n" + "\n".join(rows) + "\n")
    return q


def test_a_trajectory_job_matches_the_function_called_directly(job_client, server_dir, crba):
    q = write_trajectory(server_dir / "trajectory.csv", 25, seed=7)
    params = {"urdf": str(ARM7), "spec": str(SPECS / "crba.json"), "data": str(server_dir / "trajectory.csv"),
              "out": "mass.csv"}
    job_id = job_client.submit_job("trajectory", params)
    assert job_id in [job.job_id for job in job_client.jobs()]
    info = job_client.wait_job(job_id, timeout=120)
    assert info.state == "SUCCEEDED", info.error
    assert info.kind == "trajectory" and info.progress == 1.0 and info.messages

    result = job_client.job_result(job_id)
    assert result.info.job_id == job_id and result.info.state == "SUCCEEDED"
    assert result.result["knots"] == 25 and result.result["backend"] == "compiled"
    table = np.genfromtxt(os.path.join(result.result_dir, "mass.csv"), delimiter=",", names=True)
    values = [name for name in table.dtype.names if name.startswith("value")]
    assert len(values) == 49
    np.testing.assert_allclose(table["t"], 0.01 * np.arange(25), rtol=0, atol=1e-15)
    for k in range(25):  # the local function built by `robodiff warmup` (conftest), called here
        expected = crba(q=q[k])["value"].ravel()
        got = np.array([table[name][k] for name in values])
        np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-12, err_msg=f"knot {k}")

    assert job_client.cancel_job(job_id) == "SUCCEEDED"  # a finished job keeps its state


def test_a_running_job_can_be_cancelled(job_client, server_dir):
    write_trajectory(server_dir / "slow.csv", 5, seed=3)
    # The humanoid's ABA Jacobian: seconds of compiling before the first knot.
    params = {"urdf": str(REPO / "examples" / "robots" / "humanoid.urdf"), "floating_base": True,
              "spec_json": {"function": "aba", "outputs": [{"kind": "value"}, {"kind": "jacobian", "wrt": ["q"]}]},
              "data": str(server_dir / "slow.csv")}
    job_id = job_client.submit_job("trajectory", json.dumps(params))
    assert job_client.cancel_job(job_id) == "CANCELLED"
    info = job_client.wait_job(job_id, timeout=30)
    assert info.state == "CANCELLED"
    with pytest.raises(robodiff.Error) as raised:
        job_client.job_result(job_id)
    assert raised.value.code == "FAILED_PRECONDITION" and "CANCELLED" in raised.value.message


def test_bad_parameters_are_refused_naming_the_field(job_client):
    with pytest.raises(robodiff.Error) as raised:
        job_client.submit_job("trajectory", {"urdf": str(ARM7), "spec": str(SPECS / "crba.json")})
    assert raised.value.code == "INVALID_ARGUMENT" and "data" in raised.value.message
    with pytest.raises(robodiff.Error, match="INVALID_ARGUMENT"):
        job_client.submit_job("no-such-kind", {})


def test_an_unknown_job_is_not_found(job_client):
    for call in (job_client.job_status, job_client.job_result):
        with pytest.raises(robodiff.Error) as raised:
            call("no-such-job")
        assert raised.value.code == "NOT_FOUND" and "no-such-job" in raised.value.message

