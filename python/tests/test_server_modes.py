"""Client("shm") and Client("dds") against a real robodiffd (server_fixtures.py): values
against the double reference (`robodiff compute --backend reference`), the C++ client
(`robodiff eval` on the same server) and finite differences; batches against single calls;
a server killed (UNAVAILABLE) and restarted (the same Function works again: the client
registers its models and functions again, docs/client.md "Server restarts")."""

import json
import subprocess
import time

import numpy as np
import pytest

import robodiff
from conftest import ARM7, robodiff_cli
from server_fixtures import SHM_SERVICE, loopback_dds, robodiffd, roudi  # noqa: F401 (fixtures)

# RNEA with its Jacobian wrt [q, v, a], built quickly (O1, no -march=native) as in the C++
# end-to-end tests: the server interprets it at once and compiles it in the background.
SPEC = {"function": "rnea", "outputs": [{"kind": "value"}, {"kind": "jacobian", "wrt": ["q", "v", "a"]}],
        "build": {"optimization": "O1", "march_native": False}}
RNG = np.random.default_rng(23)
STATE = {name: RNG.uniform(-1.0, 1.0, 7) for name in ("q", "v", "a")}
TIMEOUT_S = 5.0  # per call: a test never waits longer than this for one answer


class Remote:
    """A Client insisting on one transport, arm7 loaded, the RNEA Jacobian function."""

    def __init__(self, mode: str, address: str) -> None:
        self.mode = mode
        self.address = address
        self.client = robodiff.Client(address, timeout=TIMEOUT_S)
        self.model = self.client.load(ARM7)
        self.rnea = self.model.function(SPEC)


@pytest.fixture(scope="module", params=["shm", "dds"])
def remote(request, robodiffd) -> Remote:  # noqa: F811 (the imported fixture)
    return Remote(request.param, robodiffd.address(request.param))


@pytest.fixture(scope="module")
def files(tmp_path_factory) -> dict:
    """The spec and the state as files, for the CLI."""
    directory = tmp_path_factory.mktemp("cli")
    (directory / "spec.json").write_text(json.dumps(SPEC))
    (directory / "state.json").write_text(json.dumps({k: v.tolist() for k, v in STATE.items()}))
    return {"spec": directory / "spec.json", "state": directory / "state.json"}


def run_cli(*arguments: str) -> dict:
    done = subprocess.run([str(robodiff_cli()), *arguments], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, f"robodiff {' '.join(arguments)} failed: {done.stderr}"
    return json.loads(done.stdout)


@pytest.fixture(scope="module")
def reference(files) -> dict:
    """RNEA and its Jacobian in doubles, no generated code, no server."""
    return run_cli("compute", "--urdf", str(ARM7), "--spec", str(files["spec"]), "--backend", "reference",
                   "--state", str(files["state"]), "--derivatives")


def test_the_client_uses_the_transport_it_insists_on(remote):
    assert remote.client.mode == remote.mode
    assert remote.rnea.mode == remote.mode
    assert (remote.model.nq, remote.model.nv) == (7, 7)
    assert remote.rnea.outputs == {"value": (7,), "jacobian": (7, 21)}


def test_values_match_the_reference_and_the_cpp_client(remote, reference, files):
    got = remote.rnea(**STATE)
    np.testing.assert_allclose(got["value"], reference["value"], rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(got["jacobian"], np.array(reference["jacobian"]), rtol=1e-10, atol=1e-12)
    cpp = run_cli("eval", "--server", remote.address, "--timeout", str(TIMEOUT_S), "--urdf", str(ARM7),
                  "--spec", str(files["spec"]), "--state", str(files["state"]))
    assert cpp["model_id"] == remote.model.id and cpp["function_id"] == remote.rnea.id
    np.testing.assert_allclose(got["value"], cpp["value"], rtol=1e-12, atol=1e-13)
    np.testing.assert_allclose(got["jacobian"], np.array(cpp["jacobian"]), rtol=1e-12, atol=1e-13)


def test_the_jacobian_matches_central_differences_of_the_value(remote):
    x = np.concatenate([STATE["q"], STATE["v"], STATE["a"]])
    h = 1e-6
    steps = np.concatenate([np.eye(21) * h, -np.eye(21) * h])  # knot k: x + e_k h, knot 21 + k: x - e_k h
    knots = x + steps
    tau = remote.rnea(q=knots[:, :7].copy(), v=knots[:, 7:14].copy(), a=knots[:, 14:].copy())["value"]
    differences = ((tau[:21] - tau[21:]) / (2 * h)).T  # column k: d tau / d x_k
    np.testing.assert_allclose(remote.rnea(**STATE)["jacobian"], differences, rtol=1e-6, atol=1e-6)


def test_a_batch_equals_single_calls(remote):
    knots = 13
    inputs = {name: RNG.uniform(-1.0, 1.0, (knots, 7)) for name in ("q", "v", "a")}
    batch = remote.rnea(**inputs)
    assert batch["value"].shape == (knots, 7) and batch["jacobian"].shape == (knots, 7, 21)
    for k in range(knots):
        single = remote.rnea(**{name: x[k] for name, x in inputs.items()})
        np.testing.assert_allclose(batch["value"][k], single["value"], rtol=1e-12, atol=1e-13)
        np.testing.assert_allclose(batch["jacobian"][k], single["jacobian"], rtol=1e-12, atol=1e-13)


def compiled_event(server, function_id: str, timeout: float = 60.0):
    """The current server's log line saying that it compiled the function or loaded its
    library from the cache (None if neither came within `timeout` s)."""
    return server.wait_for_event(lambda e: e.get("function_id") == function_id
                                 and e.get("event") in ("function_compiled", "function_loaded"), timeout)


def test_the_server_compiles_the_function_and_the_library_gives_the_reference_values(remote, robodiffd,  # noqa: F811
                                                                                     reference):
    assert compiled_event(robodiffd, remote.rnea.id) is not None, robodiffd.log()
    got = remote.rnea(**STATE)
    np.testing.assert_allclose(got["value"], reference["value"], rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(got["jacobian"], np.array(reference["jacobian"]), rtol=1e-10, atol=1e-12)


def test_a_killed_server_is_unavailable_and_a_restarted_one_serves_the_same_function(remote, robodiffd):  # noqa: F811
    # The library in the cache first (the interpreter serves until then), so that the
    # restarted server has it at once.
    assert compiled_event(robodiffd, remote.rnea.id) is not None, robodiffd.log()
    before = remote.rnea(**STATE)
    try:
        robodiffd.kill()
        started = time.monotonic()
        with pytest.raises(robodiff.Error) as raised:
            remote.rnea(**STATE)
        assert raised.value.code == "UNAVAILABLE", str(raised.value)
        assert "went away" in raised.value.message  # the transport saw it go, no mere timeout
        assert time.monotonic() - started < TIMEOUT_S, "UNAVAILABLE only at the call's deadline"
    finally:
        robodiffd.start()
    # The new server knows nothing: the client registers arm7 and the function again (same
    # ids: content hashes) and retries, behind the same Function.
    after = remote.rnea(**STATE)
    np.testing.assert_allclose(after["value"], before["value"], rtol=1e-12, atol=1e-13)
    np.testing.assert_allclose(after["jacobian"], before["jacobian"], rtol=1e-12, atol=1e-13)
    loaded = robodiffd.wait_for_event(lambda e: e.get("event") == "function_loaded", TIMEOUT_S)
    assert loaded is not None and loaded["function_id"] == remote.rnea.id, robodiffd.log()
    assert loaded["source"] == "cache", "the restarted server should load the cached library"
    assert remote.client.load(ARM7).id == remote.model.id
    assert remote.model.function(SPEC).id == remote.rnea.id


def test_shm_without_a_server_on_the_service_is_unavailable(roudi):  # noqa: F811
    with pytest.raises(robodiff.Error) as raised:
        robodiff.Client(f"shm:{SHM_SERVICE}-nobody", timeout=0.5)
    assert raised.value.code == "UNAVAILABLE"
    assert "-nobody" in raised.value.message
