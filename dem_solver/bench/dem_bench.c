/* dem_bench — granular settle benchmark of the DEM solver.
 *
 *   dem_bench N STEPS [--threads T] [--write-liggghts FILE]
 *
 * N spheres (radius 4.9-5 mm, Hertz–Mindlin, μ = 0.5, ε = 0.5) start on a laterally jittered
 * lattice of 40 layers (spacing 2.02 R across, 2 R up: columns already touching; the box
 * widens with N) in a box of five planes
 * and settle under gravity for STEPS steps of 5e-5 s (the lattice buckles and rearranges). Prints one line: spheres, steps, threads, seconds,
 * particle-steps per second, contacts per sphere at the end. --write-liggghts writes the same
 * initial state as a LIGGGHTS data file (atom_style granular) and the box size for
 * dem_solver/bench/in.settle, so both codes run the identical settle.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dem_sim.h"
#include "nc_clock.h"

static double uniform(unsigned long long *s)
{
    *s = *s * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*s >> 11) / 9007199254740992.0;
}

int main(int argc, char **argv)
{
    if (argc < 3) {
        fprintf(stderr, "usage: dem_bench N STEPS [--threads T] [--write-liggghts FILE]\n");
        return 2;
    }
    long n = atol(argv[1]), steps = atol(argv[2]);
    int threads = 0;
    const char *lig = NULL;
    for (int k = 3; k < argc; k++) {
        if (strcmp(argv[k], "--threads") == 0 && k + 1 < argc) threads = atoi(argv[++k]);
        else if (strcmp(argv[k], "--write-liggghts") == 0 && k + 1 < argc) lig = argv[++k];
        else {
            fprintf(stderr, "dem_bench: unknown argument %s\n", argv[k]);
            return 2;
        }
    }
    if (n < 1 || steps < 1) {
        fprintf(stderr, "dem_bench: N and STEPS must be >= 1\n");
        return 2;
    }
    nc_error err;
    dem_sim s;
    dem_sim_init(&s);
    snprintf(s.model.source, sizeof s.model.source, "dem_bench");
    s.model.prm.threads = threads;
    s.model.prm.dt_auto = 0;
    s.model.prm.dt_s = 5e-5;
    dem_material m;
    memset(&m, 0, sizeof m);
    snprintf(m.name, sizeof m.name, "gravel");
    m.youngs_modulus_pa = 5e6;
    m.poisson_ratio = 0.25;
    m.density_kg_m3 = 2500;
    m.restitution = 0.5;
    m.friction = 0.5;
    if (dem_sim_add_material(&s, &m, &err) < 0) goto fail;
    double R = 0.005, a = 2.02 * R, c = 2.0 * R;
    /* 40 layers whatever N: the settle (and the contacts per sphere) then evolve the same way
     * for every size, so the cost per particle-step is comparable across sizes */
    long nx = (long)ceil(sqrt((double)n / 40.0));
    long nz = (n + nx * nx - 1) / (nx * nx);
    double L = (double)nx * a + 0.1 * R;
    unsigned long long rng = 12345;
    double *xyz = malloc(3 * (size_t)n * sizeof *xyz), *rad = malloc((size_t)n * sizeof *rad);
    double *vel = malloc(3 * (size_t)n * sizeof *vel);
    if (!xyz || !rad || !vel) return 1;
    for (long i = 0; i < n; i++) {
        long x = i % nx, y = (i / nx) % nx, z = i / (nx * nx);
        rad[i] = R * (0.98 + 0.02 * uniform(&rng));
        double p[3] = {0.05 * R + 0.5 * a + (double)x * a + 0.02 * R * (uniform(&rng) - 0.5),
                       0.05 * R + 0.5 * a + (double)y * a + 0.02 * R * (uniform(&rng) - 0.5),
                       R + (double)z * c};
        double v[3] = {0.05 * (uniform(&rng) - 0.5), 0.05 * (uniform(&rng) - 0.5), 0.0};
        memcpy(xyz + 3 * i, p, sizeof p);
        memcpy(vel + 3 * i, v, sizeof v);
        if (dem_sim_add_sphere(&s, p, rad[i], 0, v, NULL, &err)) goto fail;
    }
    const double planes[5][6] = {{0, 0, 0, 0, 0, 1}, {0, 0, 0, 1, 0, 0}, {L, 0, 0, -1, 0, 0},
                                 {0, 0, 0, 0, 1, 0}, {0, L, 0, 0, -1, 0}};
    for (int k = 0; k < 5; k++)
        if (dem_sim_add_plane(&s, planes[k], planes[k] + 3, NULL, 0, &err)) goto fail;
    if (dem_sim_prepare(&s, &err)) goto fail;
    if (lig) {
        FILE *f = fopen(lig, "w");
        if (!f) {
            fprintf(stderr, "dem_bench: cannot write %s\n", lig);
            return 1;
        }
        double top = (double)nz * c + 10 * R;
        fprintf(f, "LIGGGHTS data file written by dem_bench (%ld spheres)\n\n%ld atoms\n1 atom types\n\n", n, n);
        fprintf(f, "%.9g %.9g xlo xhi\n%.9g %.9g ylo yhi\n%.9g %.9g zlo zhi\n\nAtoms\n\n",
                -0.01 * R, L + 0.01 * R, -0.01 * R, L + 0.01 * R, -0.01 * R, top);
        for (long i = 0; i < n; i++)
            fprintf(f, "%ld 1 %.17g %.17g %.17g %.17g %.17g\n", i + 1, 2.0 * rad[i], 2500.0,
                    xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
        fprintf(f, "\nVelocities\n\n");
        for (long i = 0; i < n; i++)
            fprintf(f, "%ld %.17g %.17g %.17g 0 0 0\n", i + 1, vel[3 * i], vel[3 * i + 1], vel[3 * i + 2]);
        fclose(f);
        printf("box %.17g\n", L);
    }
    free(xyz);
    free(rad);
    free(vel);
    double t0 = nc_clock_now_s();
    for (long k = 0; k < steps; k++)
        if (dem_sim_step(&s, s.model.prm.dt_s, &err)) goto fail;
    double wall = nc_clock_now_s() - t0;
    printf("dem_solver: %ld spheres, %ld steps, %d thread(s): %.3f s, %.3e particle-steps/s, "
           "%.2f contacts/sphere, kinetic energy %.4g J, %ld neighbour-list builds\n", n, steps,
           s.work.n_buffers, wall, (double)n * (double)steps / wall, (double)s.contact.list.n / (double)n,
           dem_sim_kinetic_energy(&s), s.nlist.n_builds);
    dem_sim_free(&s);
    return 0;
fail:
    fprintf(stderr, "dem_bench: %s\n", err.message);
    dem_sim_free(&s);
    return 1;
}
