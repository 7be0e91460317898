"""The stability check, both ways on learned networks: a network that reads the measured state (the
thesis's command model) is flagged by its loop gain and oscillates in closed loop; the reference-window
feed-forward with a low-gain PI is quiet and is not. Hand-made PI loops bracket the margin."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import thesis_spring

from seadesign.corrector.closedloop import run_closed_loop
from seadesign.corrector.dataset import DatasetSpec, build_dataset
from seadesign.corrector.export import NumpyCorrector, numpy_arrays
from seadesign.corrector.ilc import ILCSettings
from seadesign.corrector.imitation import ImitationSettings, train_imitation
from seadesign.corrector.recordings import recording_from_table
from seadesign.corrector.runtime import HallPI, NetCorrector, NoCorrection, ReferenceFeedForward
from seadesign.corrector.splits import make_split
from seadesign.corrector.stability import MIN_MODULUS_MARGIN, measure_loop_gain
from seadesign.corrector.train import TrainConfig, fit
from seadesign.twin import Trial

pytestmark = pytest.mark.slow  # trains two networks and runs 15 closed and broken loops: about a minute

TRIALS = [Trial("front", 0.1, 6.0), Trial("right", 0.2, 6.0), Trial("rotate_right", 0.05, 6.0)]


@pytest.fixture(scope="module")
def learned():
    """A command-task MLP trained on a simulated run without correction (as `seadesign train --model mlp
    --task command` on recordings), and a small reference-window network on ILC labels."""
    spring = thesis_spring()
    run = run_closed_loop(NoCorrection(), spring, [Trial(d, s, 10.0) for d in ("front", "right") for s in (0.05, 0.15)])
    rec = recording_from_table(run.recording, "sim")[0]
    spec = DatasetSpec("command", ("motor_vel", "hall_vel", "effort"), 0, True)
    ds = build_dataset([rec], spec)
    mlp = fit(ds, make_split(ds, "time_blocks"), spring["k_Nm_per_rad"], TrainConfig(threads=1))
    imitation = ImitationSettings(speeds=(0.075, 0.15), conditions=("hanging",), k_scales=(1.0,), trial_s=6.0,
                                  ilc=ILCSettings(max_iterations=40))
    ref = train_imitation(spring, imitation)
    return spring, NetCorrector(NumpyCorrector(numpy_arrays(mlp.net)), spec, "mlp"), \
        ReferenceFeedForward(NumpyCorrector(numpy_arrays(ref.training.net)), imitation.window, spring["k_Nm_per_rad"],
                             kp=0.1, ki=0.5, name="reference+pi")


def test_loop_gain_flags_the_learned_state_feedback_network_that_oscillates(learned):
    spring, mlp, _ = learned
    gain = measure_loop_gain(mlp, spring, TRIALS)
    run = run_closed_loop(mlp, spring, TRIALS)
    assert gain.flagged and run.oscillating
    assert gain.crossover_gain > 1.0  # measured 1.24 (margin 0.09): L passes -1 on the unstable side


def test_loop_gain_stays_quiet_on_the_learned_feed_forward(learned):
    spring, _, ref = learned
    gain = measure_loop_gain(ref, spring, TRIALS)
    run = run_closed_loop(ref, spring, TRIALS)
    assert not gain.flagged and not run.oscillating and not run.unstable
    assert gain.modulus_margin > 0.8  # measured 0.91: only the PI's kp = 0.1 closes a loop
    none = run_closed_loop(NoCorrection(), spring, TRIALS)
    # measured 0.0072 against 0.137 rad (on speeds and trials the labels did not cover)
    assert np.nanmean(np.abs(run.hall - run.target)) < 0.15 * np.nanmean(np.abs(none.hall - none.target))


def test_loop_gain_of_hand_made_loops(learned):
    """No feedback: L = 0 exactly. The thesis PI: margin 0.85. A high-gain PI that is unstable in closed loop:
    its L crosses the negative real axis beyond -1 (measured -1.95)."""
    spring = learned[0]
    none = measure_loop_gain(NoCorrection(), spring, TRIALS)
    assert none.peak_gain == 0.0 and none.modulus_margin == 1.0 and not none.flagged
    pi = measure_loop_gain(HallPI(), spring, TRIALS)
    assert 0.75 < pi.modulus_margin < 0.95 and not pi.flagged
    high = measure_loop_gain(HallPI(kp=3.0, ki=5.0, name="high_gain"), spring, TRIALS)
    assert high.flagged and high.crossover_gain > 1.0
    assert MIN_MODULUS_MARGIN == 0.5
