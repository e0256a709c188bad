/* cpl_relax_methods — the one list of relaxation methods. Adding a method: its file
 * cpl_relax_<name>.c exporting `const cpl_relax_ops cpl_relax_<name>` (see cpl_relax_ops.h)
 * and one line X(cpl_relax_<name>) in CPL_RELAX_METHOD_LIST below, which both declares it
 * and enters it in the table. */
#include "cpl_relax_ops.h"

#include <string.h>

/* in documentation order (messages list the names in this order) */
#define CPL_RELAX_METHOD_LIST(X) \
    X(cpl_relax_none)            \
    X(cpl_relax_constant)        \
    X(cpl_relax_aitken)          \
    X(cpl_relax_iqn_ils)

#define DECLARE_METHOD(ops) extern const cpl_relax_ops ops;
#define LIST_METHOD(ops) &ops,
CPL_RELAX_METHOD_LIST(DECLARE_METHOD)
static const cpl_relax_ops *const methods[] = {CPL_RELAX_METHOD_LIST(LIST_METHOD) NULL};

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
