"""Corrector training: learn to cancel the SEA's position error, starting from the spring's k.

Flow: recordings -> `build_dataset` (task, modalities, history, positive) -> `make_split`
(time blocks / by recording / the thesis's random 80/20) -> `fit` -> `export_bundle`
(TorchScript + NumPy) -> open-loop and closed-loop evaluation against the baselines.
"""

from seadesign.corrector.dataset import CorrectorDataset, DatasetSpec, FeatureBuilder, Recording, build_dataset
from seadesign.corrector.export import NumpyCorrector, export_bundle, load_numpy, load_torchscript
from seadesign.corrector.modalities import COMBINATIONS, MODALITIES
from seadesign.corrector.models import MODEL_KINDS, CorrectorNet
from seadesign.corrector.runtime import FeedForward, HallPI, NetCorrector, NoCorrection
from seadesign.corrector.splits import SPLITS, Split, make_split
from seadesign.corrector.train import TrainConfig, TrainResult, fit

__all__ = [
    "COMBINATIONS", "MODALITIES", "MODEL_KINDS", "SPLITS", "CorrectorDataset", "CorrectorNet", "DatasetSpec",
    "FeatureBuilder", "FeedForward", "HallPI", "NetCorrector", "NoCorrection", "NumpyCorrector", "Recording", "Split",
    "TrainConfig", "TrainResult", "build_dataset", "export_bundle", "fit", "load_numpy", "load_torchscript",
    "make_split",
]
