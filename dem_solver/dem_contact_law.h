/* dem_contact_law — the contact force law as a strategy: one table of operations per law, one
 * file per law (dem_law_hertz.c, dem_law_linear.c), one list (dem_contact_laws[] in
 * dem_contact_law.c, in the order of the dem_law enum and of contact_law's names).
 *
 * Contract: everything about a law that is not the per-contact force of a step goes through
 * its table: the name, the parameter check, the pair constant sqrt(kt / kn'), the normal
 * state at an overlap with the derivatives the interface Jacobian needs, the critical time
 * step, the contact time that limits an automatic dt, the elastic energy of the normal spring.
 * The per-contact force itself (dem_contact_force() in dem_contact_hertz.h, the hot path of the
 * DEM) is NOT called through the table: a call through a pointer per contact would pass the
 * small vectors through memory and cannot be inlined. It stays an always_inline function that
 * switches once on the dem_law enum (a compile-time dispatch: each branch is the law's inline
 * normal part; the tangential part is common). A new law adds its table here and its branch
 * there; the table's normal() must give the same normal force as that branch.
 */
#ifndef DEM_CONTACT_LAW_H
#define DEM_CONTACT_LAW_H

#include "dem_contact_hertz.h"
#include "dem_model.h"
#include "nc_error.h"

typedef struct dem_sim dem_sim;

/* Normal state of a contact at overlap δ (no dashpot, no clamp): the normal force is
 * fn = fn_elastic + 2 ζ cn_root δ̇, clamped to >= 0; the tangential spring stiffness kt; and
 * their derivatives with respect to δ. */
typedef struct dem_law_normal {
    double fn_elastic;   /* N */
    double kn_tangent;   /* dfn_elastic/dδ (N/m) */
    double cn_root;      /* sqrt(m* kn') (the dashpot is 2 ζ cn_root, N s/m) */
    double dcn_root;     /* d cn_root / dδ */
    double kt;           /* tangential stiffness (N/m) */
    double dkt;          /* d kt / dδ */
} dem_law_normal;

typedef struct dem_contact_law {
    const char *name;    /* the contact_law value of dem.json */
    dem_damping_formula default_damping; /* dem.json "damping" when not given */
    const char *section; /* dem.json object the law needs (NULL: none) */
    const char *section_example; /* its smallest content, for the message when it is missing */
    int no_tension;      /* 1: the normal force is clamped to >= 0 */
    /* Checks the law's parameters after loading (err names the missing one). */
    int (*check)(const dem_params *prm, const char *source, nc_error *err);
    /* sqrt(kt / kn') of a pair with effective moduli E*, G* (for the tangential dashpot). */
    double (*kt_kn_root)(const dem_params *prm, double e_star, double g_star);
    void (*normal)(const dem_params *prm, const dem_pair *pair, double overlap,
                   dem_law_normal *out);
    /* Critical time step of the model (s) and the contact time at impact speed v (s; INFINITY
     * when the law sets no such limit), both for an automatic dt. */
    double (*critical_dt)(const dem_sim *s);
    double (*contact_time)(const dem_sim *s, double v);
    /* Elastic energy of the normal spring at overlap δ (J). */
    double (*elastic_energy)(const dem_params *prm, const dem_pair *pair, double overlap);
} dem_contact_law;

extern const dem_contact_law dem_law_hertz;  /* dem_law_hertz.c */
extern const dem_contact_law dem_law_linear; /* dem_law_linear.c */
/* All laws, indexed by dem_law, NULL-terminated. */
extern const dem_contact_law *const dem_contact_laws[];

static inline const dem_contact_law *dem_contact_law_of(dem_law law)
{
    return dem_contact_laws[law];
}

#endif
