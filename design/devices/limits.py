"""Material limits the devices' design problems take as defaults."""

from __future__ import annotations

from simulator import SU8

__all__ = ["SU8_TG"]

#: Glass transition temperature [deg C] of SU-8, the crease polymer of the paper's devices, read
#: from the material (:data:`simulator.SU8`, 210 deg C); problems take it as default.
SU8_TG = SU8.glass_transition
