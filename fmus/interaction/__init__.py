"""What couples the catenary and the pantographs (thesis 3.2-3.3): the layer above both
models and below the FMU slaves and the master.

- :mod:`.contact_laws`: the contact laws by scenario name (registry in
  :mod:`.contact_registry`): :mod:`.penalty_contact`, :mod:`.constraint_contact`
- :mod:`.coupled`: the monolithic coupled system (structure, bodies, contacts)
- :mod:`.condensed`: the monolithic step condensed on the contact points
- :mod:`.prescribed`: pantographs moved along prescribed heights
- :mod:`.catenary_start`, :mod:`.pantograph_start`: the FMUs' start handshakes

The package itself imports none of them.
"""
