"""Robot and bench formats: round trips, and every validation error names line/row/column."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from seadesign.data import (
    RECORDING_COLUMNS,
    read_bench,
    read_metadata,
    read_recording,
    write_bench,
    write_recording,
)
from seadesign.errors import DataError

HEADER = (",l_knee_pos,l_hall_pos,l_knee_vel,l_hall_vel,l_knee_eff,r_knee_pos,r_hall_pos,"
          "r_knee_vel,r_hall_vel,r_knee_eff,imu,l_pressure,r_pressure,command,timestamp")
IMU = '"[0.0, 0.0, 0.0, 1.0, 0.1, 0.2, 0.3, 0.0, 0.0, 9.81]"'
PRESS = '"[1.0, 2.0, 3.0, 4.0]"'
CMD = '"[1.1, 0.0, 0.0, -1.0, -1.1, 0.0, 0.0, -1.0]"'


def _row(i: int, t: float, cmd: str = "[]", l_pos: str = "1.0", imu: str = IMU) -> str:
    return f"{i},{l_pos},0.98,0.0,0.0,0.5,-1.0,-0.97,0.0,0.0,-0.5,{imu},{PRESS},{PRESS},{cmd},{t}"


def _write(tmp_path, lines: list[str], header: str = HEADER):
    path = tmp_path / "rec.csv"
    path.write_text("\n".join([header] + lines) + "\n")
    return path


def test_reader_parses_lists_into_named_columns(tmp_path):
    path = _write(tmp_path, [_row(0, 100.0), _row(1, 100.01, CMD)])
    df = read_recording(path)
    assert list(df.columns) == RECORDING_COLUMNS
    assert df["time_s"].tolist() == pytest.approx([0.0, 0.01])
    assert df["imu_qw"].tolist() == [1.0, 1.0] and df["imu_acc_z"].iloc[0] == 9.81
    assert df["r_pressure_3"].iloc[0] == 4.0
    assert df["has_command"].tolist() == [False, True]
    assert np.isnan(df["l_cmd_pos"].iloc[0]) and df["l_cmd_pos"].iloc[1] == 1.1
    assert df["r_cmd_max_current"].iloc[1] == -1.0
    assert read_metadata(path) is None and df.attrs["metadata"] is None


@pytest.mark.parametrize(
    "lines, header, match",
    [
        ([_row(0, 1.0)], HEADER.replace(",l_hall_vel", ""), r"missing column\(s\) 'l_hall_vel'"),
        ([_row(0, 1.0), _row(1, 2.0, l_pos="abc")], HEADER, r"line 3 \(data row 1\), column 'l_knee_pos'.*'abc'"),
        ([_row(0, 1.0, l_pos="")], HEADER, r"line 2 \(data row 0\), column 'l_knee_pos': is empty"),
        ([_row(0, 1.0), _row(1, 0.5)], HEADER, r"line 3 \(data row 1\), column 'timestamp'.*does not increase"),
        ([_row(0, 1.0), _row(1, 1.0)], HEADER, r"column 'timestamp'.*does not increase"),
        ([_row(0, 1.0, imu='"[0.0, 1.0]"')], HEADER, r"column 'imu': list has 2 value\(s\), expected 10"),
        ([_row(0, 1.0, cmd='"[1.0, 2.0, 3.0]"')], HEADER, r"column 'command': list has 3 value\(s\), expected 0 or 8"),
        ([_row(0, 1.0, imu="0.5")], HEADER, r"column 'imu': '0.5' is not a list"),
        ([_row(0, 1.0, imu='"[' + ", ".join(["x"] * 10) + ']"')], HEADER, r"column 'imu'.*non-numeric"),
        ([_row(0, 1.0, l_pos="nan")], HEADER, r"column 'l_knee_pos': value 'nan' is not a finite number"),
        ([], HEADER, r"no data rows"),
    ],
)
def test_reader_refuses_malformed_files(tmp_path, lines, header, match):
    with pytest.raises(DataError, match=match):
        read_recording(_write(tmp_path, lines, header))


def test_reader_refuses_missing_and_empty_files(tmp_path):
    with pytest.raises(DataError, match="does not exist"):
        read_recording(tmp_path / "nope.csv")
    (tmp_path / "empty.csv").write_text("")
    with pytest.raises(DataError, match="empty"):
        read_recording(tmp_path / "empty.csv")


def test_recording_round_trip_is_exact_with_sidecar(tmp_path):
    path = _write(tmp_path, [_row(0, 100.0), _row(1, 100.0125, CMD), _row(2, 100.02)])
    df = read_recording(path)
    out = write_recording(df, tmp_path / "copy.csv", metadata={"seed": 3})
    back = read_recording(out)
    pd.testing.assert_frame_equal(df, back)
    assert back.attrs["metadata"] == {"seed": 3}


def _bench(n: int = 5, temperature: bool = False) -> pd.DataFrame:
    t = np.arange(n) * 0.1
    df = pd.DataFrame({"time_s": t, "torque_Nm": np.sin(t), "deflection_rad": np.sin(t) / 9.106})
    if temperature:
        df["temperature_C"] = 23.0 + t
    return df


@pytest.mark.parametrize("temperature", [False, True])
def test_bench_round_trip(tmp_path, temperature):
    df = _bench(temperature=temperature)
    back = read_bench(write_bench(df, tmp_path / "b.csv", metadata={"k": 1}))
    pd.testing.assert_frame_equal(df, back)
    assert back.attrs["metadata"] == {"k": 1}


@pytest.mark.parametrize(
    "text, match",
    [
        ("time_s,torque_Nm\n0,1\n", r"missing column\(s\) 'deflection_rad'"),
        ("time_s,torque_Nm,deflection_rad,torque_nm\n0,1,2,3\n", r"unknown column\(s\) 'torque_nm'"),
        ("time_s,torque_Nm,deflection_rad\n0,1,2\n1,x,2\n", r"line 3 \(data row 1\), column 'torque_Nm'"),
        ("time_s,torque_Nm,deflection_rad\n0,1,2\n0,1,2\n", r"line 3 \(data row 1\), column 'time_s'.*does not increase"),
        ("time_s,torque_Nm,deflection_rad,temperature_C\n0,1,2,\n", r"column 'temperature_C': is empty"),
    ],
)
def test_bench_reader_refuses_malformed_files(tmp_path, text, match):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(DataError, match=match):
        read_bench(path)


def test_bench_writer_refuses_bad_tables(tmp_path):
    df = _bench()
    df.loc[2, "torque_Nm"] = np.nan
    with pytest.raises(DataError, match="data row 2, column 'torque_Nm'"):
        write_bench(df, tmp_path / "b.csv")
