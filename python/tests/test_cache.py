"""robodiff.cache.ls against `robodiff cache ls --json`, the SQLite index and the files
on disk, for the session cache the real `robodiff warmup` filled (conftest.py)."""

import dataclasses
import datetime
import hashlib
import json
import sqlite3
import subprocess

import pytest

import robodiff
from conftest import WARMED_SPECS, robodiff_cli


def cli_entries(cache_dir):
    command = [str(robodiff_cli()), "cache", "ls", "--json", "--cache", str(cache_dir)]
    return json.loads(subprocess.run(command, check=True, capture_output=True, text=True, timeout=60).stdout)


def test_ls_shows_what_the_cli_shows(cache_dir):
    entries = robodiff.cache.ls(cache_dir)
    assert len(entries) == len(WARMED_SPECS)
    assert [dataclasses.asdict(e) for e in entries] == cli_entries(cache_dir)


def test_ls_agrees_with_the_sqlite_index_and_the_files(cache_dir, arm7):
    index = sqlite3.connect(f"file:{cache_dir / 'index.sqlite'}?mode=ro", uri=True)
    rows = {key: (robot, function, size, sha) for key, robot, function, size, sha in index.execute(
        "SELECT key, robot, function, total_bytes, library_sha256 FROM entries WHERE state = 'ready'")}
    index.close()
    entries = robodiff.cache.ls(cache_dir)
    assert {e.key: (e.robot, e.function, e.total_bytes, e.library_sha256) for e in entries} == rows
    assert sorted(e.function for e in entries) == ["crba", "rnea", "rnea"]
    for entry in entries:
        library = cache_dir / "objects" / entry.key[:2] / entry.key / "library.so"
        assert hashlib.sha256(library.read_bytes()).hexdigest() == entry.library_sha256
        assert entry.library_bytes == library.stat().st_size
        assert entry.model_hash == arm7.id and entry.state == "ready"
        assert entry.spec["function"] == entry.function
        age = datetime.datetime.now(datetime.timezone.utc) - entry.created_at
        assert datetime.timedelta(0) <= age < datetime.timedelta(hours=1)


def test_ls_is_most_recently_used_first_and_counts_loads(cache_dir, crba):
    entries = robodiff.cache.ls(cache_dir)  # the crba fixture loaded its library from the cache
    used = [e.last_used for e in entries]
    assert used == sorted(used, reverse=True)
    [loaded] = [e for e in entries if e.function == "crba"]
    assert loaded.hits >= 1 and loaded.last_used_at is not None


def test_a_directory_never_built_in_is_empty(tmp_path):
    assert robodiff.cache.ls(tmp_path / "nothing-here") == []
    assert not (tmp_path / "nothing-here").exists()  # ls creates nothing


def test_a_path_that_is_no_directory_is_an_error_naming_it(tmp_path):
    path = tmp_path / "a-file"
    path.write_text("not a cache")
    with pytest.raises(robodiff.Error) as raised:
        robodiff.cache.ls(path)
    assert raised.value.code == "FAILED_PRECONDITION" and str(path) in raised.value.message


def test_default_dir_follows_the_environment(tmp_path, monkeypatch):
    monkeypatch.setenv("ROBODIFF_CACHE_DIR", str(tmp_path / "elsewhere"))
    assert robodiff.cache.default_dir() == tmp_path / "elsewhere"
    assert robodiff.cache.ls() == []
