"""Ctrl-C (SIGINT to the process group) and SIGTERM (to the main process, as a job scheduler
sends it) stop a running sweep within 2 s, with the local executor and with Dask: the workers and
what they started are gone, no half-written file is left, the finished candidates are saved and
the printed command resumes the run. A real `seadesign sweep` process and real signals."""

from __future__ import annotations

import os
import re
import shlex
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import psutil
import pytest
from click.testing import CliRunner

from seadesign.cli import main
from sweep_helpers import write_tiny_study

REPO = Path(__file__).resolve().parents[1]
STOP_WITHIN_S = 2.0


def _start(study: Path, tmp: Path, executor: str) -> subprocess.Popen:
    cmd = [sys.executable, "-c", "from seadesign.cli import main; main()", "sweep", str(study), "--jobs", "2",
           "--out", str(tmp / "out"), "--cache-dir", str(tmp / "cache"), "--executor", executor]
    env = dict(os.environ, PYTHONPATH=str(REPO))
    return subprocess.Popen(cmd, cwd=tmp, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)  # its own process group, as a terminal's foreground job


def _running_in_group(pgid: int) -> list[psutil.Process]:
    alive = []
    for p in psutil.process_iter(["status"]):
        try:
            if os.getpgid(p.pid) == pgid and p.info["status"] != psutil.STATUS_ZOMBIE:
                alive.append(p)
        except (ProcessLookupError, psutil.Error):
            continue
    return alive


@pytest.mark.parametrize("executor, sig, target", [
    pytest.param("local", signal.SIGINT, "group", id="local-ctrl-c", marks=pytest.mark.slow),  # ~70 s; SIGTERM stays
    pytest.param("local", signal.SIGTERM, "main", id="local-sigterm"),
    pytest.param("dask", signal.SIGINT, "group", id="dask-ctrl-c", marks=pytest.mark.slow),
    pytest.param("dask", signal.SIGTERM, "main", id="dask-sigterm", marks=pytest.mark.slow),
])
def test_signal_stops_the_sweep_promptly_and_cleanly(tmp_path, executor, sig, target):
    study = write_tiny_study(tmp_path, beam_count="[3, 4, 5, 6]")  # four valid candidates
    proc = _start(study, tmp_path, executor)
    rows = tmp_path / "out" / "tiny" / "rows"
    deadline = time.monotonic() + 300
    while not (rows.is_dir() and any(rows.glob("*.json"))):
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline, "no candidate finished within 300 s"
        time.sleep(0.05)
    time.sleep(0.5)  # the next candidates are now mid-way (meshing or solving)
    assert proc.poll() is None, "the sweep finished before it could be interrupted"
    t0 = time.monotonic()
    (os.killpg if target == "group" else os.kill)(proc.pid, sig)
    _, err = proc.communicate(timeout=30)
    stopped_s = time.monotonic() - t0
    assert stopped_s < STOP_WITHIN_S, f"took {stopped_s:.2f} s to stop"
    assert proc.returncode == 128 + sig
    time.sleep(0.2)
    assert not _running_in_group(proc.pid), "worker processes outlived the sweep"
    assert not list(tmp_path.rglob("*.tmp")), "half-written files were left"
    saved = len(list(rows.glob("*.json")))
    match = re.search(rf"stopped by {sig.name}: (\d+) of 4 candidates finished and saved.*resume with: (.*)", err)
    assert match, err
    assert int(match.group(1)) == saved >= 1
    resume = shlex.split(match.group(2))
    assert resume[:2] == ["seadesign", "sweep"] and str(study) in resume

    if executor == "local" and sig == signal.SIGINT:  # the printed command resumes where it stopped
        result = CliRunner().invoke(main, resume[1:] + ["--quiet"])
        assert result.exit_code == 0, result.output
        assert f"{4 - saved} computed, {saved} reused" in result.output
        assert (pd.read_csv(tmp_path / "out" / "tiny" / "results.csv")["status"] == "ok").all()
