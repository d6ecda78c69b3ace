"""Compiled functions of a mode's state, in the run's own number type.

Where the gap is not linear in the coordinates (arc chains, curves), the
collision callbacks need the gap, its gradient, the law's metric sigma at
the contact and the gap's acceleration and jerk at the instant of contact
(see system._contact_terms); the driver needs each body's centre, normal
force, metric and driving force (checks at the start, outputs). heyoka
compiles them once per mode shape (``cfunc``), with the mode's runtime
parameters, so they are evaluated in the same type as the integration.
"""

from __future__ import annotations

import heyoka as hy
import numpy as np

from .compiled_cache import CompiledCache

#: Values per contact in a contact function: gap, dgap/dq_i, dgap/dq_j, sigma_i, sigma_j, gap'', gap'''.
CONTACT_VALUES = 7
#: Values per body in a body function: x_C, y_C, N/m, sigma, driving force per unit mass, q''.
BODY_VALUES = 6

_COMPILED = CompiledCache(64)


def _compiled(key, outputs, variables, precision):
    def build():
        options = {} if precision.name == "double" else {"fp_type": precision.fp_type}
        if precision.name.startswith("mp:"):
            options["prec"] = precision.bits
        return hy.cfunc(outputs, vars=variables, **options)

    return _COMPILED.get(key, build)


def contact_function(system):
    """``f(state, pars) -> array``: CONTACT_VALUES numbers per watched contact, in order."""
    outputs = [x for values in system.contact_expressions for x in values]
    if not outputs:
        return None
    return _compiled(("contact", system.shape), outputs, system.variables, system.precision)


def body_function(system):
    """``f(state, pars) -> array``: BODY_VALUES numbers per body (free modes only), or None."""
    outputs = [x for values in system.body_expressions for x in values]
    if not outputs:
        return None
    return _compiled(("body", system.shape), outputs, system.variables, system.precision)


def motion_function(system):
    """``f(state, pars, time) -> array``: psi'' and psi\'\'\' per unit (the circle with friction or forcing), or None."""
    outputs = [x for values in system.unit_motion for x in values]
    if not outputs:
        return None
    return _compiled(("motion", system.shape), outputs, system.variables, system.precision)


def link_function(system):
    """``f(state, pars) -> array``: gap, dgap/dq_i, dgap/dq_j per link of a cluster (not linear gaps), or None."""
    outputs = [x for values in system.link_terms for x in values]
    if not outputs:
        return None
    return _compiled(("links", system.shape), outputs, system.variables, system.precision)


def evaluate(function, state, pars, t=0.0):
    """Call a compiled function on one state with the mode's parameters (numpy arrays of the run's type)
    at time ``t`` (forced systems). A state without the slip velocities of a rough track's
    rolling bodies (a full state, or a reduced one) is taken as rolling: slips 0."""
    state = np.asarray(state)
    # Zeros and the time in the state's own number type and precision (heyoka's real128 and real
    # dtypes: np.zeros of the real dtype made reals of precision 2, measured).
    zero = state.flat[0] * 0
    if state.size < function.nvars:
        state = np.concatenate([state, np.array([zero] * (function.nvars - state.size), dtype=state.dtype)])
    kwargs = {}
    if function.is_time_dependent:
        kwargs["time"] = t if isinstance(t, type(zero)) else zero + t
    if function.nparams == 0:
        return function(state, **kwargs)
    return function(state, pars=np.asarray(pars)[: function.nparams], **kwargs)
