"""vmcl: the MIT Vision Machine (Poggio et al.) rebuilt on OpenCL.

Each Connection Machine processor of the original becomes one OpenCL work-item; the host schedules
whole-field operations. Importing vmcl compiles nothing and touches no OpenCL device: the first call
that needs one creates :func:`default_machine` lazily.
"""

from vmcl.machine import Machine, NoOpenCLPlatformError, default_machine

__all__ = ["Machine", "NoOpenCLPlatformError", "default_machine"]
__version__ = "0.1.0"
