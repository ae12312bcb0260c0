"""The checks of a scenario against its catenary, before anything is built: the speed below
the EN 50119 limit, the analysis window inside the model, every pantograph's passage on the
line, the model's size. Each failure is one :class:`~pantocosim.core.errors.ParameterError`
naming the scenario's field.
"""

from __future__ import annotations

import dataclasses

from pantocosim.catenary.mesh import estimate_dofs
from pantocosim.catenary.operating_height import passage_duration
from pantocosim.core.errors import ParameterError
from pantocosim.master.scenario import Scenario
from pantocosim.master.size_limits import MAX_DOFS, check_catenary_size, culprit

#: EN 50119: operating speed at most 0.7 of the contact-wire wave speed
MAX_WAVE_SPEED_RATIO = 0.7


def check_speed(sc: Scenario, wave: float, force: bool) -> None:
    """The speed at most :data:`MAX_WAVE_SPEED_RATIO` of the wave speed ``wave`` [m/s]
    (unless ``force``)."""
    if sc.speed > MAX_WAVE_SPEED_RATIO * wave and not force:
        raise ParameterError("speed_kmh", sc.speed_kmh,
                             f"exceeds {MAX_WAVE_SPEED_RATIO} of the contact-wire wave speed "
                             f"c = {wave * 3.6:.0f} km/h (EN 50119 limit "
                             f"{MAX_WAVE_SPEED_RATIO * wave * 3.6:.0f} km/h); use --force to "
                             f"run anyway", sc.source)


def analysis_window(sc: Scenario, definition) -> tuple[tuple[float, float], str, float]:
    """(window [m], the scenario field that sets it, duration [s]): the analysis window
    inside the model and the run's duration (by default
    :func:`~pantocosim.catenary.operating_height.passage_duration`)."""
    support_x = definition.support_x
    length = float(support_x[-1])
    src = sc.source
    if sc.window_supports is not None:
        i, j = sc.window_supports
        if j > definition.n_spans:
            raise ParameterError("analysis.window_supports", list(sc.window_supports),
                                 f"the model has supports 0..{definition.n_spans}", src)
        window = (float(support_x[i]), float(support_x[j]))
        wfield = "analysis.window_supports"
    else:
        window = sc.window_m
        wfield = "analysis.window_m"
        if window[0] < 0 or window[1] > length:
            raise ParameterError(wfield, list(window),
                                 f"outside the model (0 .. {length:g} m)", src)
    if sc.duration_s is None:
        duration = passage_duration(window[1], [p.position_m for p in sc.pantographs],
                                    sc.speed)
    else:
        duration = sc.duration_s
    return window, wfield, float(duration)


def check_passages(sc: Scenario, definition, window, wfield: str, duration: float) -> None:
    """Every pantograph starts on the line before the analysis window, is raised (ramp
    start) before it and stays on the line until the run ends."""
    src = sc.source
    length = float(definition.support_x[-1])
    dfield = "simulation.duration_s" if sc.duration_s is not None else wfield
    dvalue = sc.duration_s if sc.duration_s is not None else list(window)
    for k, p in enumerate(sc.pantographs):
        if not (0.0 < p.position_m < length):
            raise ParameterError(f"pantographs[{k}].position_m", p.position_m,
                                 f"must lie on the line (0 .. {length:g} m)", src)
        if p.position_m > window[0]:
            raise ParameterError(f"pantographs[{k}].position_m", p.position_m,
                                 f"past the start of the analysis window ({wfield} starts "
                                 f"at {window[0]:g} m); a pantograph starts before it", src)
        if p.ramp is not None and p.ramp.start_m + p.ramp.length_m > window[0]:
            raise ParameterError(f"pantographs[{k}].ramp.length_m", p.ramp.length_m,
                                 f"the raising ends at x = "
                                 f"{p.ramp.start_m + p.ramp.length_m:g} m, inside the analysis "
                                 f"window ({window[0]:g} .. {window[1]:g} m); it must end "
                                 "before the window", src)
        if p.ramp is not None:
            z = float(definition.design_contact_height(p.position_m)[0])
            if p.ramp.lowered_height >= z:
                raise lowered_above_wire(sc, k, z)
        end = p.position_m + sc.speed * duration
        if end >= length:
            raise ParameterError(dfield, dvalue,
                                 f"pantograph {k + 1} would run past the end of the model "
                                 f"(x = {end:.0f} m > {length:g} m) before the run ends", src)
        if end < window[1]:
            raise ParameterError("simulation.duration_s", duration,
                                 f"too short: pantograph {k + 1} does not reach the end of "
                                 f"the analysis window", src)


def lowered_above_wire(sc: Scenario, k: int, z_wire: float) -> ParameterError:
    p = sc.pantographs[k]
    return ParameterError(f"pantographs[{k}].ramp.lowered_height", p.ramp.lowered_height,
                          f"not below the contact wire at the start ({z_wire:.3f} m at "
                          f"x = {p.position_m:g} m); a lowered pantograph is out of "
                          "contact", sc.source)


def check_size(sc: Scenario, base, definition, element_size, max_dofs, n_steps) -> int:
    """Size guard of the scenario's catenary model (before it is built): names the input
    that makes it large (``--element-size``, the scenario's ``spans`` or the catenary
    file's field)."""
    limit = MAX_DOFS if max_dofs is None else max_dofs
    if element_size is not None:
        definition = dataclasses.replace(definition, element_size=element_size)
        field, value, source = "--element-size", element_size, None
    elif sc.spans and estimate_dofs(base) <= limit:
        field, value, source = "spans", sc.spans, sc.source
    else:
        (field, value), source = culprit(base), base.source
    return check_catenary_size(definition, field, value, source, limit, n_steps)
