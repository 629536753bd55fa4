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

__all__ = ["Client", "Error", "Function", "Model"]
