"""``input_offset`` on an input: the plant receives :math:`u + \\delta` where the recording says
:math:`u` (a current or force sensor's bias, an actuator's zero off its command's).

On an integrating plant (a cell's charge, a carriage's position) a small bias is a drift that grows
over the record; where the input's source enters one junction linearly (a force, a current) it is
the same record as a constant load there, and the held-out choice says so
(:func:`diagnosis.alternatives.indistinguishable`)."""
from __future__ import annotations

from ..catalogue_common import ParamSpec, fresh_name
from .base import Kind, Proposal, register
from .signal_common import input_record

#: the fit's further starts beside its guess 0, as fractions of the input's recorded span (the
#: offset's effect is linear on a linear plant, but an offset that shifts a nonlinear law's
#: operating point, a valve's, is not)
START_SHARES = (-0.02, 0.02)


@register
class InputOffset(Kind):
    name = "input_offset"
    doors = ("input",)

    def propose(self, site):
        record = input_record(site)
        name = fresh_name(site.taken, f"offset_{site.name}")
        width = record.width
        return [Proposal((ParamSpec(name, 0.0, -width, width, record.unit,
                                    f"offset of what input {site.name} delivers from its record"),),
                         starts=tuple({name: share * width} for share in START_SHARES))]

    def build(self, graph, cand, values):
        u = cand.place.name
        return graph.route_input(u, f"({u} + {cand.params[0].name})")

    def explain(self, cand, values, show):
        u = cand.place.name
        return (f"the plant receives {u} {show(cand.params[0].name)} off its record: an offset of "
                f"the {u} sensor or of the actuator's zero on input {u}")
