/* fem_element — the registry of element types (see fem_element.h). A new type is its file
 * fem_element_<type>.c, defining its table of operations, and one line below. */
#include "fem_element.h"

#include <string.h>

extern const fem_element_ops fem_element_cable_ops;
extern const fem_element_ops fem_element_post_ops;
extern const fem_element_ops fem_element_brake_ops;
extern const fem_element_ops fem_element_sliding_cable_ops;
extern const fem_element_ops fem_element_ring_ops;

/* FEM_TYPE_CABLE is the first entry (the default of an element set). */
static const fem_element_ops *const registry[] = {
    &fem_element_cable_ops,
    &fem_element_post_ops,
    &fem_element_brake_ops,
    &fem_element_sliding_cable_ops,
    &fem_element_ring_ops,
};

#define N_TYPES ((int)(sizeof registry / sizeof *registry))

const fem_element_ops *fem_element_type(int type)
{
    return type >= 0 && type < N_TYPES ? registry[type] : NULL;
}

int fem_element_find(const char *name)
{
    for (int i = 0; i < N_TYPES; i++)
        if (strcmp(registry[i]->name, name) == 0) return i;
    return -1;
}

const char *fem_element_names(char *buf, size_t size, const char *sep)
{
    size_t len = 0;
    if (size) buf[0] = '\0';
    for (int i = 0; i < N_TYPES && len + 1 < size; i++) {
        const char *parts[2] = {i ? sep : "", registry[i]->name};
        for (int p = 0; p < 2; p++)
            for (const char *c = parts[p]; *c && len + 1 < size; c++) buf[len++] = *c;
        buf[len] = '\0';
    }
    return buf;
}

void fem_element_bar_mass(double rhoA, double L0, int lumped, double *m11, double *m12)
{
    double m = rhoA * L0;
    if (lumped) {
        *m11 = 0.5 * m;
        *m12 = 0.0;
    } else {
        *m11 = m / 3.0;                                /* eq. (11): rho A L / 6 * 2 */
        *m12 = m / 6.0;
    }
}
