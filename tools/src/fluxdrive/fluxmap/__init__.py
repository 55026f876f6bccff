"""Flux maps of saturated synchronous machines (docs/flux-maps.md): the
analytic model, map files (NPZ, CSV), validation, frame conversion, the
MTPA / MTPV tables of Varatharajan et al. 2022 (29)-(31), the .fdmap blob
and its C table."""

from .errors import FluxMapError
from .model import FluxMap

__all__ = ["FluxMap", "FluxMapError"]
