/* dem_detect — the out-of-line functions shared by the detectors (dem_detect.h): appending to a
 * spill list and emitting one wall contact. */
#include "dem_detect.h"

int dem_spill_add(dem_spills *sp, int kind, int32_t index, double weight, const double f[3],
                  const double t[3])
{
    if (sp->n == sp->cap) {
        size_t cap = sp->cap ? 2 * sp->cap : 256;
        dem_spill *r = realloc(sp->r, cap * sizeof *r);
        if (!r) return -1;
        sp->r = r;
        sp->cap = cap;
    }
    dem_spill *r = &sp->r[sp->n++];
    r->kind = kind;
    r->index = index;
    r->weight = weight;
    for (int k = 0; k < 3; k++) {
        r->f[k] = f[k];
        r->t[k] = t ? t[k] : 0.0;
    }
    return 0;
}

int dem_emit_wall_contact(const dem_sim *s, dem_emit_ctx *ctx, size_t i, dem_contact_in *in,
                          double dt)
{
    double ft[3], kt_prev, fn_prev, impact_speed;
    int32_t p;
    long c = dem_new_record(s, ctx, i, in->kind, in->j, in->aux, ft, &kt_prev, &fn_prev,
                            &impact_speed, &p);
    if (c < 0) return -1;
    if (p >= 0 && (in->kind == DEM_CONTACT_NET_EDGE || in->kind == DEM_CONTACT_NET_NODE)) {
        /* A cable has no inside: if the normal flipped since the last step, the sphere
         * centre crossed the line (the net moved more than the overlap in one step).
         * Keep the side of the ongoing contact and count the crossing as overlap, so
         * the net pushes the sphere back instead of letting it through. */
        const double *np = s->contact.prev.normal + 3 * (size_t)p;
        if (np[0] * in->n[0] + np[1] * in->n[1] + np[2] * in->n[2] < 0.0) {
            double dist = in->reach - in->overlap;
            in->overlap = in->reach + dist;
            for (int k = 0; k < 3; k++) in->n[k] = -in->n[k];
            in->lever_i = fmax(0.0, s->model.sph.radius[i] - 0.5 * in->overlap);
        }
    }
    const double *v_i = s->model.sph.vel + 3 * i;
    const double *w_i = s->model.bod.omega + 3 * (size_t)s->model.sph.body[i];
    double r_i[3] = {in->lever_i * in->n[0], in->lever_i * in->n[1], in->lever_i * in->n[2]};
    double wr[3];
    dem_cross3(w_i, r_i, wr);
    double vc[3]; /* eq. (A.2) */
    for (int k = 0; k < 3; k++) vc[k] = in->v_other[k] - (v_i[k] + wr[k]);
    double f[3], t[3];
    dem_contact_force(&s->model.prm, &in->pair, in->overlap, in->n, vc, dt, ft, &kt_prev, &fn_prev,
                      &impact_speed, f);
    dem_store_record(ctx->out, (size_t)c, ft, kt_prev, fn_prev, impact_speed, in->overlap, in->n);
    dem_cross3(r_i, f, t);
    if (dem_add_to_sphere(s, ctx, i, f, t)) return -1;
    /* the reaction -f on the wall, summed after the pass */
    int32_t index = in->kind == DEM_CONTACT_MESH ? in->aux : in->j;
    return dem_spill_add(ctx->spill, in->kind, index, in->weight, f, NULL);
}
