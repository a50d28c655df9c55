"""`mrsim.load_rows`: a run folder's streamed file read up to a cut run's
torn last row, which it reports; a bad row elsewhere is an error with the
file and line."""

import pytest

import mrsim


def test_a_torn_last_row_is_left_out_and_reported(tmp_path):
    f = tmp_path / "timing.csv"
    f.write_text("tick,robot,sent_ns,status\n0,r0,5,accepted\n1,r0,6,acc")
    got = mrsim.load_rows(f)
    assert got.rows == [{"tick": "0", "robot": "r0", "sent_ns": "5", "status": "accepted"}]
    assert got.cut is not None and got.cut.startswith(f"{f}:3: the run was cut")
    whole = tmp_path / "events.jsonl"
    whole.write_text('{"type": "agent_joined"}\n{"type": "go')
    got = mrsim.load_rows(whole)
    assert got.rows == [{"type": "agent_joined"}]
    assert got.cut.startswith(f"{whole}:2:")


def test_a_bad_middle_row_is_an_error_naming_file_and_line(tmp_path):
    f = tmp_path / "trajectory.csv"
    f.write_text("tick,time,body\n0,0,r0\n1,0.1\n2,0.2,r0\n")
    with pytest.raises(ValueError, match=r"trajectory.csv:3: 2 fields, the header has 3"):
        mrsim.load_rows(f)
    e = tmp_path / "events.jsonl"
    e.write_text('{"a": 1}\nnot json\n{"b": 2}\n')
    with pytest.raises(ValueError, match=r"events.jsonl:2: "):
        mrsim.load_rows(e)

