"""The penalty contact law, re-exported for the master (it lives in
:mod:`pantocosim.core.contact` so that the FMUs bundle the same single implementation)."""

from pantocosim.core.contact import PenaltyContact

__all__ = ["PenaltyContact"]
