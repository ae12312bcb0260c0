"""Scenario text of the short tests: three spans of en50318 under one 2-mass pantograph,
250 km/h, the window of one span (add a ``[simulation]`` table to change the model)."""

THREE_SPANS = """\
name = "three-spans"
catenary = "en50318"
spans = 3
speed_kmh = 250.0

[[pantographs]]
model = "en50318-2mass"
position_m = 30.0
start = "static"

[analysis]
window_supports = [1, 2]
"""

#: the linear catenary (the fastest reference-grade run)
LINEAR = '\n[simulation]\ncatenary_model = "linear"\n'
