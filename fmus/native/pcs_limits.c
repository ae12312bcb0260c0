/* The checks of the native FMUs' limits (pcs_limits.h). */
#include "pcs_limits.h"

#include <math.h>
#include <stdio.h>

#include "pcs_model.h"

long pcs_substeps(double H, double h, char *err)
{
    double ratio = H / h, n;
    if (!(isfinite(H) && H > 0.0)) {
        snprintf(err, PCS_MSG, "communication step %.17g s: must be finite and > 0", H);
        return -1;
    }
    if (!(ratio < PCS_MAX_SUBSTEPS + 0.5)) {
        snprintf(err, PCS_MSG, "communication step %.17g s is more than %d internal steps of "
                 "%.17g s", H, PCS_MAX_SUBSTEPS, h);
        return -1;
    }
    n = floor(ratio + 0.5);
    if (n < 1.0 || fabs(ratio - n) > 1e-9 * (ratio > 1.0 ? ratio : 1.0)) {
        snprintf(err, PCS_MSG, "communication step %.17g s is not a whole number of internal "
                 "steps of %.17g s (the step this FMU was exported for)", H, h);
        return -1;
    }
    return (long)n;
}

int pcs_within(const char *name, double value, double lo, double hi, const char *unit,
               char *err)
{
    if (value >= lo && value <= hi) return 0;
    snprintf(err, PCS_MSG, "%s = %.17g%s: must lie in [%g, %g]%s",
             name, value, unit, lo, hi, unit);
    return -1;
}

int pcs_fixed_real(const char *name, double exported, double value, char *err)
{
    double tol = 1e-12 * (fabs(exported) > 1.0 ? fabs(exported) : 1.0);
    if (isfinite(value) && fabs(value - exported) <= tol) return PCS_OK;
    snprintf(err, PCS_MSG, "%s = %.17g: this native FMU was exported with %s = %.17g (export "
             "it again with pantocosim export-native to change it)", name, value, name, exported);
    return PCS_ERROR;
}
