/* dem_contact_law — the list of contact laws (indexed by dem_law). */
#include "dem_contact_law.h"

const dem_contact_law *const dem_contact_laws[] = {&dem_law_hertz, &dem_law_linear, NULL};
