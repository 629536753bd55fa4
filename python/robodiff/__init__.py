"""robodiff from Python: a robot's dynamics and their derivatives as numpy arrays.

    import numpy as np, robodiff
    client = robodiff.Client("local")          # the cached library, in this process
    model = client.load("examples/robots/arm7.urdf")
    rnea = model.function("examples/specs/rnea_jacobian.json")
    out = rnea(q=np.zeros(7), v=np.zeros(7), a=np.zeros(7))  # {"value": ..., "jacobian": ...}

The reference is docs/python.md.
"""

from .errors import Error
from ._robodiff import Function
from .client import Client, Model
from .jobs import JobInfo, JobResult
from .warmup import WarmupResult, WarmupSummary, warmup
from . import cache
from . import reference
from .spec_check import CheckComparison, CheckResult, check

__all__ = ["Client", "Error", "Function", "Model", "JobInfo", "JobResult", "WarmupResult", "WarmupSummary",
           "cache", "warmup"]
__all__ += ["CheckComparison", "CheckResult", "check", "reference"]
