"""Corrector training: learn to cancel the SEA's position error, starting from the spring's k.

Flow: recordings -> `build_dataset` (task, modalities, history, positive) -> `make_split`
(time blocks / by recording / the thesis's random 80/20) -> `fit` -> `export_bundle`
(TorchScript, ONNX, NumPy) -> open-loop (`open_loop_table`) and closed-loop (`closed_loop_table`, knee
simulator) evaluation against the baselines; `iterate` retrains on runs with the corrector in the
loop. The correctors that work in closed loop learn in the knee simulator instead: the reference network on ILC
labels (`imitation`), the closed-loop policy (the default) fine-tuning it through the loop (`closedloop_training`).
`train_bundle` / `train_reference_bundle` / `train_closedloop_bundle` / `evaluate_bundles` (`workflow`)
are the CLI's workflows.
"""

from seadesign.corrector.closedloop import ClosedLoopRun, closed_loop_table, run_closed_loop
from seadesign.corrector.dataset import CorrectorDataset, DatasetSpec, FeatureBuilder, Recording, build_dataset
from seadesign.corrector.evaluate import open_loop_table
from seadesign.corrector.export import NumpyCorrector, export_bundle, load_numpy, load_torchscript
from seadesign.corrector.iterative import iterate
from seadesign.corrector.modalities import COMBINATIONS, MODALITIES
from seadesign.corrector.models import MODEL_KINDS, CorrectorNet
from seadesign.corrector.recordings import load_recordings
from seadesign.corrector.runtime import FeedForward, HallPI, NetCorrector, NoCorrection
from seadesign.corrector.splits import SPLITS, Split, make_split
from seadesign.corrector.train import TrainConfig, TrainResult, fit
from seadesign.corrector.workflow import evaluate_bundles, load_corrector, train_bundle

__all__ = [
    "ClosedLoopRun", "closed_loop_table", "evaluate_bundles", "iterate", "load_corrector", "load_recordings",
    "open_loop_table", "run_closed_loop", "train_bundle",
    "COMBINATIONS", "MODALITIES", "MODEL_KINDS", "SPLITS", "CorrectorDataset", "CorrectorNet", "DatasetSpec",
    "FeatureBuilder", "FeedForward", "HallPI", "NetCorrector", "NoCorrection", "NumpyCorrector", "Recording", "Split",
    "TrainConfig", "TrainResult", "build_dataset", "export_bundle", "fit", "load_numpy", "load_torchscript",
    "make_split",
]
