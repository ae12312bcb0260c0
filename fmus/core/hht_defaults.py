"""The HHT-alpha integrator's defaults and limits (no numerics imported: the command line's
parsers read them)."""

#: HHT alpha of every run unless a scenario or option sets another (thesis 3.3.2: a little
#: numerical damping of the highest frequencies)
DEFAULT_ALPHA = -0.05
#: Newton residual tolerance of simulation runs, relative to the largest force in the
#: residual (:meth:`~.hht.HHTSettings.for_runs`)
RUN_RTOL = 1e-4
#: the loosest tolerance a run may set (scenario newton_rtol / coupling_rtol, catenary FMU)
RUN_RTOL_MAX = 1e-2
#: the HHT alpha range (unconditional stability, second order): alpha in [ALPHA_MIN, 0]
ALPHA_MIN, ALPHA_MAX = -1.0 / 3.0, 0.0
