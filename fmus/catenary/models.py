"""The catenary models a run can choose, by name (scenario ``[simulation] catenary_model``,
``pantocosim run --catenary-model``, the catenary FMU's Integer ``catenary_model``).

- ``nonlinear``: :class:`~.model.CatenaryModel`, the ANCF finite-element model (the
  reference);
- ``linear``: :class:`~.linear.LinearCatenary`, linearised about the static equilibrium,
  constant matrices, exact dropper slackening;
- ``modal``: :class:`~.modal.ModalCatenary`, the linear model on its modes below a cutoff
  with static corrections at the droppers and the contact points.

Every factory takes the catenary (preset, path, definition or mesh), the start positions, the
speed and the options; the FMU code of a model is its stable code in :data:`CATENARY_MODELS`
(:func:`model_code`; never a position in a list: a new model takes a new code).
"""

from __future__ import annotations

from ..core.errors import ParameterError
from ..core.registry import Registry

#: default cutoff of the modal model [Hz]: the accuracy targets against the linear
#: model on en50318-250, en50318-300 and dsa380-ave-300 (docs/modal-cutoff.md; the wire modes
#: a pantograph meets within the 20 Hz band reach 20 Hz / (1 - V/c), c the contact wire's
#: wave speed, and the study needs about 1.3 times that)
DEFAULT_MODAL_CUTOFF_HZ = 100.0


# each factory imports its own model: a catenary FMU loads the one it builds (measured: the
# FMU slaves import in 0.46 s so, 0.62 s with every catenary and pantograph model at the top)
def _nonlinear(catenary, x0, speed, element_size=None, modal_cutoff_hz=None):
    from .model import CatenaryModel

    return CatenaryModel(catenary, x0, speed, element_size=element_size)


def _linear(catenary, x0, speed, element_size=None, modal_cutoff_hz=None):
    from .linear import LinearCatenary

    return LinearCatenary(catenary, x0, speed, element_size=element_size)


def _modal(catenary, x0, speed, element_size=None, modal_cutoff_hz=None):
    from .modal import ModalCatenary

    cutoff = DEFAULT_MODAL_CUTOFF_HZ if modal_cutoff_hz is None else modal_cutoff_hz
    return ModalCatenary(catenary, x0, speed, element_size=element_size, cutoff_hz=cutoff)


#: name -> factory(catenary, x0, speed, element_size=None, modal_cutoff_hz=None), with the
#: model's code (the catenary FMU's Integer ``catenary_model``; stable, never reused)
CATENARY_MODELS = Registry("catenary model", "catenary_model", coded=True)
CATENARY_MODELS.add("nonlinear", _nonlinear, code=0)
CATENARY_MODELS.add("linear", _linear, code=1)
CATENARY_MODELS.add("modal", _modal, code=2)
#: the model names in code order
MODEL_NAMES = tuple(CATENARY_MODELS.codes())


def model_code(name: str) -> int:
    """The FMU code of the model ``name`` (the catenary FMU's ``catenary_model``)."""
    return CATENARY_MODELS.code(name)


def model_name(code_or_name) -> str:
    """The model name of an FMU code (0, 1, 2) or a name."""
    if isinstance(code_or_name, str):
        CATENARY_MODELS.entry(code_or_name)
        return code_or_name
    return CATENARY_MODELS.name_of(int(code_or_name))


def make_catenary(model, catenary, x0=(0.0,), speed: float = 0.0, *,
                  element_size: float | None = None, modal_cutoff_hz: float | None = None):
    """The catenary model ``model`` (name or FMU code) of ``catenary``."""
    if modal_cutoff_hz is not None and not modal_cutoff_hz > 0:
        raise ParameterError("modal_cutoff_hz", modal_cutoff_hz, "must be > 0")
    return CATENARY_MODELS.entry(model_name(model))(catenary, x0, speed, element_size=element_size,
                                              modal_cutoff_hz=modal_cutoff_hz)


def law_model(catenary):
    """The model behind the start laws (operating_height.py): one on the full DOFs (the
    modal model's linear model, else the model itself)."""
    return getattr(catenary, "linear", catenary)
