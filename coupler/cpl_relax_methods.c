/* cpl_relax_methods — the one list of relaxation methods. Adding a method: its file
 * cpl_relax_<name>.c (see cpl_relax_ops.h), its declaration and its table entry below. */
#include "cpl_relax_ops.h"

#include <string.h>

/* one line each: defined in cpl_relax_none.c, cpl_relax_constant.c, ... */
extern const cpl_relax_ops cpl_relax_none;
extern const cpl_relax_ops cpl_relax_constant;
extern const cpl_relax_ops cpl_relax_aitken;
extern const cpl_relax_ops cpl_relax_iqn_ils;

/* in documentation order (messages list the names in this order) */
static const cpl_relax_ops *const methods[] = {
    &cpl_relax_none,
    &cpl_relax_constant,
    &cpl_relax_aitken,
    &cpl_relax_iqn_ils,
    NULL,
};

const cpl_relax_ops *const *cpl_relax_methods(void)
{
    return methods;
}

const cpl_relax_ops *cpl_relax_method_find(const char *name)
{
    for (const cpl_relax_ops *const *m = methods; *m; m++)
        if (strcmp((*m)->name, name) == 0) return *m;
    return NULL;
}
