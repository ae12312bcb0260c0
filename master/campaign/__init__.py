"""Campaigns: many independent runs of a scenario swept over axes, executed on Dask.

``spec`` loads and validates sweep files and expands them into cases; ``axes`` maps an axis
name (``speed_kmh``, ``pantograph``, ``coupling``, ``catenary.contact_wire.tension``, any
dotted scenario field) to what it changes; ``worker`` runs one case on a Dask worker;
``execute`` drives the sweep (cluster, resume, progress); ``table`` writes the results table
(CSV and Parquet) as cases finish; ``assessment`` checks each row against the EN 50367 / TSI
criteria of an editable data file; ``report`` turns a sweep folder into plots and a summary.
See docs/campaigns.md.
"""
