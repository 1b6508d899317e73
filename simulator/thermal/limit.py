"""The crease temperature limit (theory 5.4): one measure, one verdict.

Above its glass transition the crease polymer softens, so a design keeps its creases below
1.2 T_g of the crease material (252 degC for SU-8). The limit is judged on one measure
everywhere (the CLI's ``run`` summary and ``gripper evaluate``, the design problems'
constraints, the sweeps, the heater allocation and the studies' figures): the **centre-line
mean** of a crease, the mean of its three centre-line nodes A, B, Ctr, the hottest crease
counting. The hottest crease node, 5-20 degC above it, is information shown beside it;
``measure="crease_max"`` judges the hottest node instead (stricter; an option of the design
problems and the heater allocation).

:func:`crease_limit_temperatures` is the measure, per crease; :meth:`TemperatureLimit.judge`
finds the hottest crease on it and returns a :class:`TemperatureVerdict`, the only place
that compares with the limit. Its message names the crease, the temperature on the measure
and the limit::

    crease 5: centre-line mean 261.30 degC > 1.2 T_g = 252 degC
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._result import ResultFiles
from .._validate import finite, one_of, positive
from ..errors import ParameterError
from .measures import crease_temperatures

__all__ = ["TG_FACTOR", "LIMIT_MEASURES", "crease_limit_temperatures", "TemperatureLimit",
           "TemperatureVerdict"]

#: The design limit on crease temperatures as a multiple of T_g of the crease material (paper
#: section 6.3).
TG_FACTOR = 1.2
#: What a limit can be judged on: ``"centre_line"`` (the documented measure, theory 5.4) or
#: ``"crease_max"`` (the hottest crease node), with the words messages use for them.
LIMIT_MEASURES = {"centre_line": "centre-line mean", "crease_max": "hottest node"}
#: What a hottest node shown beside a verdict on the centre line says of itself.
_INFORMATION = "information: the limit is judged on the crease centre-line mean"


def _check_measure(measure) -> str:
    return one_of("temperature_measure", measure, tuple(LIMIT_MEASURES),
                  hint="'centre_line' is the mean of each crease's three centre-line nodes, "
                       "the documented measure of the 1.2 T_g limit (theory 5.4); "
                       "'crease_max' its hottest node (stricter)")


def crease_limit_temperatures(node_values, mesh, measure: str = "centre_line") -> np.ndarray:
    """Per crease the value a temperature limit is judged on.

    Parameters
    ----------
    node_values : array (n,) or (n, ...)
        Values at the mesh nodes, node axis first: temperatures [deg C], or rises [K] or
        rises per heater watt [K/W] (the centre-line mean is linear, so it maps rises to rises).
    mesh : BarHingeMesh or SharpHingeMesh
    measure : {"centre_line", "crease_max"}
        The mean of each crease's three centre-line nodes A, B, Ctr (theory 5.4; a
        concentrated hinge: the mean of its two hinge nodes), or its hottest node.

    Returns
    -------
    ndarray (C,) or (C, ...), in ``mesh.crease_ids`` order
    """
    return crease_temperatures(node_values, mesh, _check_measure(measure))


@dataclass(frozen=True)
class TemperatureLimit:
    """A crease temperature limit and the measure it is judged on.

    Parameters
    ----------
    value : float
        The limit [deg C].
    name : str
        How messages call it: ``"1.2 T_g"`` (:meth:`of_glass_transition`), or ``"limit"``.
    measure : {"centre_line", "crease_max"}
        What it bounds (:func:`crease_limit_temperatures`); default the centre-line mean.
    """

    value: float
    name: str = "limit"
    measure: str = "centre_line"

    def __post_init__(self):
        finite("TemperatureLimit.value", self.value, "deg C")
        _check_measure(self.measure)

    @classmethod
    def of_glass_transition(cls, glass_transition: float, factor: float = TG_FACTOR,
                            measure: str = "centre_line") -> TemperatureLimit:
        """``factor`` x T_g [deg C] (default 1.2 T_g, the paper's design limit)."""
        finite("glass_transition", glass_transition, "deg C")
        positive("temperature_factor", factor)
        return cls(factor * glass_transition, f"{factor:g} T_g", measure)

    @classmethod
    def of_material(cls, material, factor: float = TG_FACTOR,
                    measure: str = "centre_line") -> TemperatureLimit | None:
        """``factor`` x T_g of a :class:`~simulator.Material`; None if its T_g is unknown."""
        tg = getattr(material, "glass_transition", None)
        return None if tg is None else cls.of_glass_transition(tg, factor, measure)

    @property
    def text(self) -> str:
        """``1.2 T_g = 252 degC``."""
        return f"{self.name} = {self.value:.4g} degC"

    @property
    def measure_words(self) -> str:
        """``centre-line mean`` or ``hottest node``."""
        return LIMIT_MEASURES[self.measure]

    def crease_temperatures(self, temperature, mesh) -> np.ndarray:
        """:func:`crease_limit_temperatures` of nodal temperatures (n,) or records (m, n)
        [deg C]: (C,) or (m, C)."""
        t = np.asarray(temperature, dtype=float)
        return crease_limit_temperatures(t.T, mesh, self.measure).T

    def judge(self, temperature, mesh, creases=None) -> TemperatureVerdict:
        """The verdict on nodal temperatures.

        Parameters
        ----------
        temperature : array (n,) or (m, n)
            Nodal temperatures [deg C] of one state, or of the m records of a history
            (``SimulationResult.history["temperature"]``): judged over all of them.
        mesh : BarHingeMesh or SharpHingeMesh
        creases : iterable of int, optional
            Crease ids judged (e.g. the heated ones); default every crease.

        Returns
        -------
        TemperatureVerdict
            The hottest judged crease on the measure, the hottest node of the judged creases
            (information), and for a history the records where they are and the first
            record above the limit.
        """
        t = np.asarray(temperature, dtype=float)
        if t.ndim not in (1, 2) or t.shape[-1] != len(mesh.nodes):
            raise ParameterError(f"temperature has shape {t.shape}; give the nodal "
                                 f"temperatures ({len(mesh.nodes)},) of a state or (m, "
                                 f"{len(mesh.nodes)}) of m records [deg C].")
        ids = np.asarray(mesh.crease_ids)
        rows = (np.arange(len(ids)) if creases is None else
                np.array([mesh.crease_row_of(c) for c in creases], dtype=int))
        if not len(rows):
            raise ParameterError("TemperatureLimit.judge: no crease to judge (the mesh has "
                                 "none, or creases is empty).")
        recs = t.reshape(-1, t.shape[-1])                                       # (m, n)
        on = crease_limit_temperatures(recs.T, mesh, self.measure)[rows].T      # (m, c)
        node = crease_limit_temperatures(recs.T, mesh, "crease_max")[rows].T
        if not np.isfinite(on).any():
            raise ParameterError("TemperatureLimit.judge: no finite crease temperature.")
        rec, j = np.unravel_index(int(np.nanargmax(on)), on.shape)
        nrec, nj = np.unravel_index(int(np.nanargmax(node)), node.shape)
        above = np.flatnonzero((on > self.value).any(axis=1))
        history = t.ndim == 2
        first = int(above[0]) if history and len(above) else None
        return TemperatureVerdict(
            self, int(ids[rows[j]]), float(on[rec, j]), float(node[nrec, nj]),
            int(ids[rows[nj]]), record=int(rec) if history else None,
            hottest_node_record=int(nrec) if history else None, first_record=first,
            first_crease=None if first is None else int(ids[rows[int(np.argmax(on[first]))]]))


@dataclass(frozen=True)
class TemperatureVerdict(ResultFiles):
    """Whether crease temperatures stay within a :class:`TemperatureLimit`.

    Attributes
    ----------
    limit : TemperatureLimit
    crease : int
        Crease id of the hottest crease on the limit's measure.
    temperature : float
        Its temperature on the measure [deg C] (the centre-line mean by default).
    hottest_node : float
        Hottest node of the judged creases [deg C]: information beside a verdict on the
        centre line, never the verdict.
    hottest_node_crease : int
        Crease id of that node.
    record, hottest_node_record : int or None
        Records of ``temperature`` and ``hottest_node`` in a judged history (None otherwise).
    first_record, first_crease : int or None
        First record of a history above the limit and its hottest crease (None if none).

    ``success`` (the limit holds: ``temperature <= limit.value``), ``status`` (``"met"`` or
    ``"exceeded"``) and ``message`` (``crease 5: centre-line mean 250.06 degC <= 1.2 T_g =
    252 degC``) follow from these.
    """

    limit: TemperatureLimit
    crease: int
    temperature: float
    hottest_node: float = math.nan
    hottest_node_crease: int | None = None
    record: int | None = None
    hottest_node_record: int | None = None
    first_record: int | None = None
    first_crease: int | None = None

    @classmethod
    def of(cls, limit: TemperatureLimit, centre_line, hottest_node) -> TemperatureVerdict:
        """The verdict from measured values: ``centre_line`` and ``hottest_node`` are
        ``(temperature [deg C], crease id)`` of the hottest crease on each measure (e.g.
        kept by a device result); the limit's measure picks the one judged."""
        judged = centre_line if limit.measure == "centre_line" else hottest_node
        return cls(limit, judged[1], float(judged[0]), float(hottest_node[0]), hottest_node[1])

    @property
    def success(self) -> bool:
        return bool(self.temperature <= self.limit.value)

    @property
    def status(self) -> str:
        return "met" if self.success else "exceeded"

    @property
    def message(self) -> str:
        """``crease 5: centre-line mean 261.30 degC > 1.2 T_g = 252 degC``."""
        return (f"crease {self.crease}: {self.limit.measure_words} {self.temperature:.2f} degC "
                f"{'<=' if self.success else '>'} {self.limit.text}")

    @property
    def constraint(self) -> float:
        """``(T - T_limit) / T_limit``, <= 0 when met (a design problem's constraint g)."""
        return (self.temperature - self.limit.value) / self.limit.value

    @property
    def margin(self) -> float:
        """``T_limit - T`` [K], positive when met."""
        return self.limit.value - self.temperature

    def information(self, where: str = "") -> str:
        """The hottest node, labelled as information (``hottest node 266.67 degC (crease 5,
        information: the limit is judged on the crease centre-line mean)``, ``where`` added
        after the crease); empty when the verdict is on the hottest node itself."""
        if self.limit.measure != "centre_line" or not math.isfinite(self.hottest_node):
            return ""
        at = [f"crease {self.hottest_node_crease}"] if self.hottest_node_crease is not None \
            else []
        at += [where] if where else []
        return f"hottest node {self.hottest_node:.2f} degC ({', '.join(at + [_INFORMATION])})"

    def to_dict(self) -> dict:
        """Flat summary, keys ``name [unit]``."""
        return {"success": self.success, "status": self.status, "message": self.message,
                "crease": self.crease, "temperature [degC]": self.temperature,
                "measure": self.limit.measure, "limit": self.limit.name,
                "limit_temperature [degC]": self.limit.value,
                "hottest_node [degC]": self.hottest_node,
                "hottest_node_crease": self.hottest_node_crease}

    _csv_name = "temperature_verdict.csv"
