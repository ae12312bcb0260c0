"""Catenary finite-element model (thesis 3.1, 3.3.3).

- :mod:`.definition`: TOML definition format, validation, presets (``load_catenary``)
- :mod:`.ancf_cable`, :mod:`.bar`, :mod:`.point_mass`, :mod:`.ground_spring`: element sets
  (numba kernels, vectorised over elements) behind one protocol
- :mod:`.supports`: support types by TOML ``type`` (one class per file, a registry)
- :mod:`.structure`: collects the element sets on one CSR pattern; :mod:`.mesh`: geometry,
  DOF numbering, elements and supports (see ``docs/architecture.md``)
- :mod:`.statics`: static equilibrium and the initial-configuration problem (3.1.3)
- :mod:`.model`: :class:`~.model.CatenaryModel`, the model the HHT-alpha integrator drives
- :mod:`.contact_point`: contact-wire points under the pantographs (3.12)-(3.13)

The package itself imports none of them: import a name from its module
(``from pantocosim.catenary.model import CatenaryModel``), so that a light module (the size
guard, the definition) does not load the model.
"""

