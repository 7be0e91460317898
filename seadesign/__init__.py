"""seadesign: design, verify and calibrate the 3D-printed torsion spring of a series elastic actuator."""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("seadesign")
except PackageNotFoundError:  # running from a source tree without install
    __version__ = "0.0.0+src"
