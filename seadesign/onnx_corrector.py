"""Run an exported corrector's ``corrector.onnx`` with ONNX Runtime: the path for a robot without
PyTorch (needs only NumPy and onnxruntime; this module imports neither torch nor the rest of
`seadesign.corrector`).

    from seadesign.onnx_corrector import load_onnx
    corrector = load_onnx("bundle/")          # or "bundle/corrector.onnx"
    u = corrector(x)                          # raw SI inputs (d,) -> command, rad; (B, d) -> (B,)

The bundle's meta.json fields (inputs, units, k, normalisation, simulator settings, ...) travel
inside the ONNX file as metadata properties and are read back into `OnnxCorrector.meta`.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from seadesign.errors import SeadesignError

ONNX_FILE = "corrector.onnx"
INSTALL = "pip install 'seadesign[onnx]' (on the robot, `pip install onnxruntime numpy` is enough)"


class OnnxCorrector:
    """corrector.onnx in one ONNX Runtime session tuned for single calls (1 thread, sequential,
    all graph optimisations; a single vector goes through input and output buffers bound once,
    which saves about a quarter of a call, so one instance serves one thread); same outputs as
    `NumpyCorrector`."""

    def __init__(self, path: str | Path) -> None:
        try:
            import onnxruntime as ort
        except ImportError as exc:
            raise SeadesignError(f"running {ONNX_FILE} needs onnxruntime; install with {INSTALL}") from exc
        opts = ort.SessionOptions()
        opts.intra_op_num_threads = 1
        opts.inter_op_num_threads = 1
        opts.execution_mode = ort.ExecutionMode.ORT_SEQUENTIAL
        opts.graph_optimization_level = ort.GraphOptimizationLevel.ORT_ENABLE_ALL
        self.session = ort.InferenceSession(str(path), opts, providers=["CPUExecutionProvider"])
        props = self.session.get_modelmeta().custom_metadata_map
        self.meta: dict[str, Any] = {k: json.loads(v) for k, v in props.items()}
        if "inputs" not in self.meta:
            raise SeadesignError(f"{path} carries no corrector metadata; export it with seadesign's export_bundle")
        self.input_names: list[str] = self.meta["inputs"]
        self.input_units: list[str] = self.meta["input_units"]
        self._input = self.session.get_inputs()[0].name
        self._outputs = [self.session.get_outputs()[0].name]
        self._x1 = np.zeros((1, len(self.input_names)), np.float32)
        self._u1 = np.zeros(1, np.float32)
        self._binding = self.session.io_binding()
        self._binding.bind_ortvalue_input(self._input, ort.OrtValue.ortvalue_from_numpy(self._x1))
        self._binding.bind_ortvalue_output(self._outputs[0], ort.OrtValue.ortvalue_from_numpy(self._u1))

    def __call__(self, x: np.ndarray) -> np.ndarray | float:
        """Raw SI inputs (d,) or (B, d), in the order of `input_names` -> command(s), rad."""
        x = np.asarray(x, dtype=np.float32)
        if x.ndim not in (1, 2) or x.shape[-1] != len(self.input_names):
            raise SeadesignError(f"the corrector takes {len(self.input_names)} inputs ({', '.join(self.input_names)}) "
                                 f"as a vector (d,) or a batch (B, d); got shape {x.shape}")
        if x.ndim == 1:
            self._x1[0] = x
            self.session.run_with_iobinding(self._binding)
            return float(self._u1[0])
        return self.session.run(self._outputs, {self._input: x})[0]


def load_onnx(bundle: str | Path) -> OnnxCorrector:
    """The ONNX Runtime path of a bundle directory (or of a corrector.onnx file itself)."""
    path = Path(bundle)
    if path.is_dir():
        path = path / ONNX_FILE
    if path.exists():
        return OnnxCorrector(path)
    meta_path = path.parent / "meta.json"
    skipped = json.loads(meta_path.read_text()).get("onnx", {}).get("skipped") if meta_path.exists() else None
    if skipped:
        raise SeadesignError(f"{path} was not exported: {skipped}, then export the bundle again")
    raise SeadesignError(f"{path} does not exist; export a bundle with `seadesign train` (needs {INSTALL})")
