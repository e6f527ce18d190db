"""rotacal — open calibration of rotary tables and the gyroscopes tested on them."""

from rotacal.errors import CaptureError, ConfigError, RotacalError

__version__ = "0.1.0"
__all__ = ["CaptureError", "ConfigError", "RotacalError", "__version__"]
