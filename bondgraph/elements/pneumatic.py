"""A pneumatic chamber as a two-port C-field: mass flow in, pressure out; elongation rate in, force out.

The chamber stores gas (pneumatic port ``pn``: absolute pressure P, Pa / mass
flow into the chamber, kg/s) and changes volume with a mechanical
displacement (port ``mech``: force F, N / elongation rate dl/dt, m/s, the
rate of the displacement ``l`` the volume depends on).  It is the capacitive
field of the pseudo-bond graph: the state is the pressure, its effort at the
pneumatic port, and the mechanical effort is a force law of the pressure and
the displacement.

Polytropic form (the default; eq. (4) of Shin et al., "Detailed dynamic
model of antagonistic PAM system", with separate indices for the flow and
the volume term)::

    dP/dt = k_1 R T mdot / V  -  k_2 (dV/dl) (dl/dt) P / V

With ``heat=`` the gas temperature becomes a state and the chamber exchanges
heat with its wall (energy balance of an ideal gas, ratio of specific heats
gamma, inflow at the wall/supply temperature, outflow at the gas
temperature, Newtonian heat flux :math:`\\dot Q = hA (T_w - T_g)` with a
constant conductance hA, W/K)::

    dP/dt   = gamma R T_in mdot / V - gamma (dV/dl) (dl/dt) P / V + (gamma - 1) hA (T_w - T_g) / V
    dT_g/dt = T_g (dP/dt / P + (dV/dl) (dl/dt) / V - R T_g mdot / (P V))

(the second from :math:`m = P V / (R T_g)`).  The gas relaxes to the wall
temperature with the time constant :math:`m c_v / hA`; as hA -> infinity the
chamber is isothermal at T_w (k_1 = k_2 = 1), as hA -> 0 adiabatic
(k_1 = k_2 = gamma).

Because the chamber is an element of its own, a graph can hang a leak (an R
to the ambient) or any other flow on the chamber's 0-junction, and a
diagnosis can replace the chamber by its thermal form.
"""
from __future__ import annotations

import re

import sympy as sp

from ..errors import DerivationError
from ..symbols import FUNCTIONS, parse, sym
from .equation import EquationElement

__all__ = ["PneumaticChamber"]


class PneumaticChamber(EquationElement):
    """Two-port pneumatic C-field with the chamber pressure as its state (see the module docstring).

    Parameters
    ----------
    name : str
        Element name.
    pressure : str
        Name of the pressure state (Pa, absolute), e.g. ``"P_1"``.
    length : str
        The displacement ``l`` the volume depends on, as an expression of the graph's
        names (m), e.g. ``"L0 - r*sin(q_psi)"``; its rate is the flow at port ``mech``.
    volume : str
        Chamber volume V(l) (m^3), an expression in ``l`` and the graph's names; dV/dl is
        derived from it.
    force : str
        Effort at port ``mech`` (N), an expression in the pressure state, ``l`` and
        ``V`` (e.g. a muscle's contraction force, eqs. (6)-(7) of the PAM paper).
    flow_index, volume_index : str
        Polytropic indices k_1 and k_2 of eq. (4) (names or numbers).
    gas_constant, temperature : str
        Specific gas constant R (J/(kg K)) and the gas/supply temperature T (K).
    heat : mapping, optional
        ``{"hA": ..., "gamma": ...}`` (W/K, 1; expressions) turns on the thermal form with
        the gas temperature state ``T_<name>`` (K), wall at `temperature`.
    initial_pressure : float
        Initial pressure (Pa).
    initial_temperature : float, optional
        Initial gas temperature (K) of the thermal form (default 293 K).
    guards, params, description
        As for :class:`~bondgraph.elements.EquationElement`.
    """

    kind = "PneumaticC"

    def __init__(self, name: str, *, pressure: str, length: str, volume: str, force: str,
                 flow_index="k1", volume_index="k2", gas_constant="R", temperature="T", heat=None,
                 initial_pressure: float = 101325.0, initial_temperature: float = 293.0, guards=None,
                 params=None, description: str = ""):
        if heat is not None and set(heat) != {"hA", "gamma"}:
            raise DerivationError(f"PneumaticC {name!r}: heat= needs exactly the keys 'hA' and 'gamma', "
                                  f"got {sorted(heat)}", element=name)
        self.pressure, self.length, self.volume, self.force = pressure, str(length), str(volume), str(force)
        self.flow_index, self.volume_index = str(flow_index), str(volume_index)
        self.gas_constant, self.temperature = str(gas_constant), str(temperature)
        self.heat = None if heat is None else {k: str(v) for k, v in heat.items()}
        self.initial_pressure, self.initial_temperature = float(initial_pressure), float(initial_temperature)
        P, R, T = pressure, self.gas_constant, self.temperature
        locals_ = {"l": self.length, "V": self.volume, "dV": _derivative(self.volume, "l", name), "F": self.force}
        initial, units = {P: self.initial_pressure}, {P: "Pa"}
        descriptions = {P: f"absolute pressure in {name}"}
        if self.heat is None:
            states = {P: f"{self.flow_index}*{R}*{T}*f_pn/V - {self.volume_index}*dV*f_mech*{P}/V"}
        else:
            gas, h_a, gamma = f"T_{name}", self.heat["hA"], self.heat["gamma"]
            # inflow at the supply temperature, outflow at the gas's (a sign, not a Piecewise on the
            # flow: sympy canonicalises a relational over the whole valve law recursively)
            locals_["T_in"] = f"({T} + {gas})/2 + ({T} - {gas})/2*sign(f_pn)"
            locals_["dP"] = (f"{gamma}*{R}*T_in*f_pn/V - {gamma}*dV*f_mech*{P}/V "
                             f"+ ({gamma} - 1)*({h_a})*({T} - {gas})/V")
            states = {P: "dP", gas: f"{gas}*(dP/{P} + dV*f_mech/V - {R}*{gas}*f_pn/({P}*V))"}
            initial[gas], units[gas] = self.initial_temperature, "K"
            descriptions[gas] = f"gas temperature in {name}"
        super().__init__(name, ports={"pn": "in", "mech": "in"}, outputs={"e_pn": P, "e_mech": "F"},
                         states=states, initial=initial, units=units, descriptions=descriptions,
                         locals=locals_, guards=guards, params=params, description=description)

    @property
    def gas_state(self) -> str:
        """Name of the gas-temperature state of the thermal form (K)."""
        return f"T_{self.name}"

    def with_heat(self, h_a: str, gamma: str, *, initial_temperature: float | None = None,
                  description: str | None = None) -> "PneumaticChamber":
        """The same chamber in its thermal form (wall conductance `h_a`, W/K; ratio of specific heats `gamma`)."""
        spec = {**self._spec(), "description": self.description}
        spec["heat"] = {"hA": str(h_a), "gamma": str(gamma)}
        if initial_temperature is not None:
            spec["initial_temperature"] = float(initial_temperature)
        if description is not None:
            spec["description"] = description
        return PneumaticChamber(self.name, **spec)

    def _spec(self):
        spec = {"pressure": self.pressure, "length": self.length, "volume": self.volume, "force": self.force,
                "flow_index": self.flow_index, "volume_index": self.volume_index,
                "gas_constant": self.gas_constant, "temperature": self.temperature,
                "initial_pressure": self.initial_pressure}
        if self.heat is not None:
            spec["heat"] = dict(self.heat)
            spec["initial_temperature"] = self.initial_temperature
        if self.params:
            spec["params"] = {k: p.to_dict() for k, p in self.params.items()}
        if self._guards:
            spec["guards"] = {g.name: g.to_dict() for g in self._guards}
        return spec


def _derivative(expression: str, variable: str, owner: str) -> str:
    """d(expression)/d(variable) as text (the volume's slope dV/dl)."""
    names = {word: sym(word) for word in re.findall(r"[A-Za-z_][A-Za-z_0-9]*", expression)
             if word not in FUNCTIONS}
    expr = parse(expression, names, owner=f"PneumaticC {owner!r} volume")
    return str(sp.diff(expr, names.get(variable, sym(variable))))
