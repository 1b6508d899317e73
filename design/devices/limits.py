"""Material limits the devices' design problems take as defaults, and the crease temperature
constraint they share (theory 5.4: 1.2 T_g judged on the crease centre-line mean, by
:class:`simulator.thermal.TemperatureLimit`)."""

from __future__ import annotations

from simulator.materials import SU8
from simulator.thermal import TG_FACTOR, TemperatureLimit

__all__ = ["SU8_TG", "SU8_LIMIT", "TemperatureLimited"]

#: Glass transition temperature [deg C] of SU-8, the crease polymer of the paper's devices, read
#: from the material (:data:`simulator.materials.SU8`, 210 deg C); problems take it as default.
SU8_TG = SU8.glass_transition
#: The design limit of the paper's devices: 1.2 T_g of SU-8 (252 deg C) on the crease
#: centre-line mean.
SU8_LIMIT = TemperatureLimit.of_glass_transition(SU8_TG, TG_FACTOR)


class TemperatureLimited:
    """Mixin of the design problems that bound the crease temperature.

    The problem (a frozen dataclass) has the fields ``glass_transition`` [deg C],
    ``temperature_factor`` and ``temperature_measure`` (``"centre_line"``, the documented
    measure, or ``"crease_max"``); its device result has ``temperature_verdict(limit)``,
    ``success`` and ``message``.
    """

    #: The limit's temperature, reported per cycle by the coordinate descent.
    report_metric = "temperature [degC]"

    @property
    def limit(self) -> TemperatureLimit:
        """``temperature_factor`` x ``glass_transition`` on ``temperature_measure``."""
        return TemperatureLimit.of_glass_transition(self.glass_transition,
                                                    self.temperature_factor,
                                                    self.temperature_measure)

    @property
    def temperature_limit(self) -> float:
        """The limit [deg C]."""
        return self.limit.value

    def _judge(self, res) -> tuple:
        """``(verdict, message)`` of a device result: the message of an evaluated design that
        exceeds the limit names the crease, its temperature and the limit (``both stages met;
        not feasible: crease 5: centre-line mean 281.02 degC > 1.2 T_g = 252 degC``)."""
        verdict = res.temperature_verdict(self.limit)
        if verdict.success or not res.success:
            return verdict, res.message
        return verdict, f"{res.message}; not feasible: {verdict.message}"
