/* What fmi3_front.c shares with fmi3_unsupported.c. */
#ifndef FMI3_FRONT_H
#define FMI3_FRONT_H

#include "fmi3Functions.h"

/* log "<function> is not supported by this FMU" and return fmi3Error */
fmi3Status pcs_fmi3_unsupported(fmi3Instance instance, const char *function);

#endif
