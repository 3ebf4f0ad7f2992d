"""fdikit.atomic: the destination is the old complete file or the new complete file, never a mix."""

import os

import pytest

from fdikit.atomic import atomic_path, write_text
from fdikit.errors import DataError


def test_write_replaces_and_leaves_no_temp(tmp_path):
    p = tmp_path / "sub" / "a.txt"
    write_text(p, "one")
    write_text(p, "two")
    assert p.read_text() == "two"
    assert sorted(os.listdir(p.parent)) == ["a.txt"]


def test_failure_in_body_keeps_old_file(tmp_path):
    p = tmp_path / "a.txt"
    write_text(p, "old")
    with pytest.raises(RuntimeError), atomic_path(p) as tmp:
        tmp.write_text("half")
        raise RuntimeError("killed mid-write")
    assert p.read_text() == "old"
    assert os.listdir(tmp_path) == ["a.txt"]


def test_failed_rename_is_a_data_error_and_keeps_old_file(tmp_path, monkeypatch):
    p = tmp_path / "a.txt"
    write_text(p, "old")

    def broken(*a, **k):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "replace", broken)
    with pytest.raises(DataError, match="a.txt.*No space left"):
        write_text(p, "new")
    assert p.read_text() == "old"
    assert os.listdir(tmp_path) == ["a.txt"]


def test_folder_destination_and_unwritable_folder(tmp_path, monkeypatch):
    with pytest.raises(DataError, match="folder"):
        write_text(tmp_path, "x")

    def denied(*a, **k):  # as mkstemp fails in a read-only folder (root ignores permission bits)
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr("tempfile.mkstemp", denied)
    with pytest.raises(DataError, match="Permission denied.*writable"):
        write_text(tmp_path / "a.txt", "x")
    assert os.listdir(tmp_path) == []
