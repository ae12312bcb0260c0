/*
 * pantocosim's C host: one program that loads FMI 2.0 and FMI 3.0 co-simulation FMUs with
 * no Python (dlopen / LoadLibrary), as a HIL rig or a C master does. It runs the native
 * FMUs of `pantocosim export-native` in a loop, or any FMU through a script of FMI calls.
 *
 * Build (one compile line; -ldl on Linux, nothing more on Windows):
 *   cc -std=c99 -O2 host_*.c -o pantocosim_host -ldl -lm     (in this folder)
 *
 * An FMU is given as the folder of the unpacked .fmu. The host reads its FMI version from
 * the fmiVersion attribute of its modelDescription.xml (2.0 or 3.0), and loads the library
 * binaries/<platform>/<modelIdentifier>.<so|dll|dylib> of its own platform: FMI 2.0 linux64,
 * win64, win32, darwin64 (aarch64 Linux: aarch64-linux); FMI 3.0 x86_64-linux,
 * aarch64-linux, x86_64-windows, x86-windows, x86_64-darwin, aarch64-darwin. The loops find
 * the variables by name in modelDescription.xml.
 *
 *   pantocosim_host forced CATENARY_DIR STEPS DT [SUBSTEPS]
 *       the catenary alone under F_k(t) = F0_k (1 + 0.1 sin(2 pi 7 t)) + 20 [t > 0.3 s]
 *       (contact_mode 0); prints "t wire_height_k wire_velocity_k ... support_uplift_j"
 *       per step with 17 digits, then the p50 / p99 / max of doStep in microseconds
 *   pantocosim_host coupled CATENARY_DIR PANTOGRAPH_DIR STEPS DT [paced]
 *       the catenary in contact_mode 1 (penalty contact inside) and a pantograph FMU: each
 *       step the pantograph's height and velocity go into the catenary, its contact force
 *       into the pantograph (zero-order hold); prints "t F z_pantograph z_wire" per step,
 *       then the p50 / p99 / max of each FMU's doStep in microseconds; "paced" waits for
 *       the wall clock at every step (busy-waiting) and counts the steps that end after
 *       their deadline t0 + (k + 1) DT
 *   pantocosim_host coupled-forces CATENARY_DIR PANTOGRAPH_DIR STEPS DT [paced]
 *       the same loop with the catenary in contact_mode 0: the host applies the penalty
 *       law F = max(0, k_H (z_pantograph - z_wire)) (k_H: the catenary's contact_stiffness)
 *       and gives F to both FMUs, as an explicit co-simulation master does
 *   pantocosim_host pantograph PANTOGRAPH_DIR STEPS DT
 *       the pantograph alone under F(t) = F0 (1 + 0.1 sin(2 pi 7 t)); prints "t z v"
 *   pantocosim_host script < CALLS
 *       one FMI call a line from standard input (the language: host_script.c)
 *
 * Every loop prints "allocations in doStep: N" (host_memory.c says what counts them).
 * Exit codes: 0 done, 2 bad input (arguments, an FMU that cannot be loaded), 4 an instance that
 * cannot be made, 5 a call that fails in a loop.
 */
#include <stdio.h>
#include <string.h>

#include "host.h"

int main(int argc, char **argv)
{
    if (argc >= 2 && !strcmp(argv[1], "script")) return host_script(stdin);
    if (argc >= 2) return host_loop(argc, argv);
    fprintf(stderr, "usage: pantocosim_host forced|coupled|coupled-forces|pantograph|script "
            "... (see host_main.c)\n");
    return 2;
}
