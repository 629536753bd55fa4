"""Client, Model and Function handles: what they report, and robodiff.Error's codes."""

import json

import numpy as np
import pytest

import robodiff
from conftest import ARM7, SPECS


def test_local_client_loads_the_arm_with_its_sizes_and_names(client, arm7):
    assert client.mode == "local"
    assert (arm7.nq, arm7.nv) == (7, 7)
    assert arm7.joint_names == [f"joint{i}" for i in range(1, 8)]
    assert "joint7" in arm7.frame_names or len(arm7.frame_names) >= 7
    assert len(arm7.id) >= 32


def test_urdf_text_and_path_give_the_same_model(client, arm7):
    assert client.load(ARM7.read_text()).id == arm7.id


def test_spec_as_dict_json_text_and_path_give_the_same_function(arm7, rnea):
    spec_text = (SPECS / "rnea_jacobian.json").read_text()
    assert arm7.function(json.loads(spec_text)).id == rnea.id
    assert arm7.function(spec_text).id == rnea.id
    assert arm7.function(str(SPECS / "rnea_jacobian.json")).id == rnea.id


def test_function_reports_its_inputs_and_outputs(rnea, rnea_sparse, crba):
    assert rnea.inputs == {"q": (7,), "v": (7,), "a": (7,)}
    assert rnea.outputs == {"value": (7,), "jacobian": (7, 21)}
    assert rnea.sparse_outputs == []
    assert rnea_sparse.sparse_outputs == ["jacobian"]
    assert crba.outputs == {"value": (7, 7)}
    assert rnea.mode == "local"
    assert "q (7,)" in repr(rnea)


def test_an_uncached_function_in_local_mode_is_failed_precondition(arm7):
    with pytest.raises(robodiff.Error) as raised:
        arm7.function(SPECS / "aba_jacobian.json")
    assert raised.value.code == "FAILED_PRECONDITION"
    assert "robodiff warmup" in raised.value.message
    assert str(raised.value).startswith("FAILED_PRECONDITION: ")


def test_a_bad_urdf_is_invalid_argument(client):
    with pytest.raises(robodiff.Error) as raised:
        client.load("<robot name='broken'><link name='a'/><joint name='j' type='revolute'></joint></robot>")
    assert raised.value.code == "INVALID_ARGUMENT"


def test_a_missing_urdf_file_is_invalid_argument_naming_it(client):
    with pytest.raises(robodiff.Error) as raised:
        client.load("/nonexistent/robot.urdf")
    assert raised.value.code == "INVALID_ARGUMENT"
    assert "/nonexistent/robot.urdf" in raised.value.message


def test_nan_inputs_are_invalid_argument_naming_the_input(rnea):
    q = np.zeros(7)
    q[3] = np.nan
    with pytest.raises(robodiff.Error) as raised:
        rnea(q=q, v=np.zeros(7), a=np.zeros(7))
    assert raised.value.code == "INVALID_ARGUMENT"
    assert "q[3]" in raised.value.message


def test_a_malformed_server_string_is_a_value_error_listing_the_forms():
    with pytest.raises(ValueError, match="auto, local, shm"):
        robodiff.Client("tcp://nowhere")


def test_local_mode_without_a_cache_is_unavailable(tmp_path):
    with pytest.raises(robodiff.Error) as raised:
        robodiff.Client("local", cache_dir=tmp_path / "absent")
    assert raised.value.code == "UNAVAILABLE"



def test_a_floating_base_adds_the_free_flyer(client):
    floating = client.load(ARM7, floating_base=True)
    assert (floating.nq, floating.nv) == (14, 13)


def test_a_spec_of_the_wrong_type_is_a_type_error(arm7):
    with pytest.raises(TypeError, match="spec: int given; a dict, a JSON string or a path is needed"):
        arm7.function(42)
