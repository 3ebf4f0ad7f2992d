"""fdikit: model-based fault detection, isolation and fault-tolerant control."""

from fdikit.errors import DataError, DesignError, FdiError, FdiWarning, ModelError, ParameterError
from fdikit.model import FaultModel

__all__ = ["FaultModel", "FdiError", "ModelError", "DesignError", "DataError", "ParameterError", "FdiWarning"]
__version__ = "0.1.0"
