/* test_checkpoint — CHECKPOINT and RESUME of bin/dem_solver (protocol/README.md §3.3).
 *
 * A granite rock (R 0.4 m, ρ 2650 kg/m³, E 3e10 Pa, COR 0.3, μ 0.5: Hertz–Mindlin with damping
 * and friction) strikes a small interface net at 10 m/s, beside a rigid cluster of three
 * granite spheres arriving at 8 m/s; the driver acts as a strong coupler (up to three SOLVEs a
 * step, the Jacobian asked for in some of them) whose structure is a compliant stand-in
 * (each iteration moves the nodes half-way to compliance × force). Run A goes through all
 * steps and checkpoints at steps 4, 9 and 14; at step 9 both bodies touch the net with
 * tangential spring history. Run B — a fresh process in A's folder, whose dem.h5 holds the
 * rows up to the end — resumes at step 9 and is given the same commands: every reply must be
 * identical bit for bit (memcmp of arrays and values), and dem.h5 (every dataset, the same row
 * counts) and the XDMF files must equal those of A. Also: only the two newest checkpoints are
 * kept, a missing checkpoint, one of another step and one of another model are refused naming
 * the file and what differs, and those refused resumes leave the results untouched (no result
 * file is created before the first BEGIN_STEP or RESUME). Needs NC_BIN (skipped otherwise). */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <hdf5.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include "dem_test_util.h"
#include "nc_file.h"
#include "proto.h"

#define NX 9                /* net nodes along x (0 .. 2 m) */
#define NY 5                /* and along y (0 .. 1 m) */
#define NN (NX * NY)
#define N_EDGES ((NX - 1) * NY + NX * (NY - 1))
#define N_STEPS 24
#define K_RESUME 9
#define DT_S 2e-4
#define COMPLIANCE_M_PER_N 1e-9

static const int checkpoint_steps[] = {4, K_RESUME, 14};

static const char *model_json =
    "{\"materials\": [{\"name\": \"granite\", \"youngs_modulus_pa\": 3e10, \"poisson_ratio\": 0.25,"
    "   \"density_kg_m3\": 2650, \"restitution\": 0.3, \"friction\": 0.5}],"
    " \"particles\": [{\"position\": [0.55, 0.45, 0.41], \"radius\": 0.4, \"velocity\": [1.5, 0.5, -10],"
    "   \"angular_velocity\": [0, 2, 0]}%s],"
    " \"clusters\": [{\"spheres\": [{\"position\": [1.45, 0.5, 0.166], \"radius\": 0.15},"
    "   {\"position\": [1.72, 0.5, 0.166], \"radius\": 0.12}, {\"position\": [1.58, 0.72, 0.166], \"radius\": 0.12}],"
    "   \"velocity\": [-1, 0.3, -8], \"angular_velocity\": [1, 0, 2]}],"
    " \"net_wall\": {\"youngs_modulus_pa\": 1e11, \"poisson_ratio\": 0.3, \"friction\": 0.3,"
    "   \"cable_radius_m\": 0.008},"
    " \"output_interval_s\": 8e-4}\n";

/* ---- a reply as bytes ------------------------------------------------------------------------ */

typedef struct blob {
    unsigned char *data;
    size_t len, cap;
} blob;

static void put(blob *b, const void *p, size_t n)
{
    if (b->len + n > b->cap) {
        size_t cap = b->cap ? 2 * b->cap : 4096;
        while (cap < b->len + n) cap *= 2;
        b->data = realloc(b->data, cap);
        assert_non_null(b->data);
        b->cap = cap;
    }
    memcpy(b->data + b->len, p, n);
    b->len += n;
}

/* Everything a reply says except its session token: header fields, every array (name, type,
 * shape, bytes) and every value (name, bits). */
static void put_reply(blob *b, const proto_message *m)
{
    put(b, &m->type, sizeof m->type);
    put(b, &m->step, sizeof m->step);
    put(b, &m->iteration, sizeof m->iteration);
    put(b, &m->time_s, sizeof m->time_s);
    put(b, &m->dt_s, sizeof m->dt_s);
    put(b, m->text, strlen(m->text) + 1);
    put(b, &m->n_arrays, sizeof m->n_arrays);
    for (size_t a = 0; a < m->n_arrays; a++) {
        const proto_array *x = &m->arrays[a];
        put(b, x->name, strlen(x->name) + 1);
        put(b, &x->dtype, sizeof x->dtype);
        put(b, x->shape, sizeof x->shape);
        if (x->count) put(b, x->data, x->count * proto_dtype_size(x->dtype));
    }
    put(b, &m->n_values, sizeof m->n_values);
    for (size_t v = 0; v < m->n_values; v++) {
        put(b, m->values[v].name, strlen(m->values[v].name) + 1);
        put(b, &m->values[v].value, sizeof m->values[v].value);
    }
}

/* ---- the driver (a coupler with a compliant stand-in structure) ----------------------------- */

typedef struct run {
    int pid;
    proto_peer *peer;
    proto_message req, rep;
    double u[3 * NN];          /* last accepted interface displacement */
    blob replies;              /* every reply from step K_RESUME on */
    long n_replies;
    double u_at_resume[3 * NN];
    double contacts_at_resume; /* net contacts reported by the last solve before K_RESUME */
    long solves_with_jacobian;
} run;

static void net_mesh(double *xyz, int32_t *ids, int32_t *elements)
{
    for (int j = 0; j < NY; j++)
        for (int i = 0; i < NX; i++) {
            int k = j * NX + i;
            xyz[3 * k] = 0.25 * i;
            xyz[3 * k + 1] = 0.25 * j;
            xyz[3 * k + 2] = 0.0;
            ids[k] = 100 + k;
        }
    int e = 0;
    for (int j = 0; j < NY; j++)
        for (int i = 0; i + 1 < NX; i++) {
            elements[2 * e] = j * NX + i;
            elements[2 * e + 1] = j * NX + i + 1;
            e++;
        }
    for (int j = 0; j + 1 < NY; j++)
        for (int i = 0; i < NX; i++) {
            elements[2 * e] = j * NX + i;
            elements[2 * e + 1] = (j + 1) * NX + i;
            e++;
        }
    assert_int_equal(e, N_EDGES);
}

static void request(run *r, int record)
{
    nc_error err;
    if (proto_peer_request(r->peer, &r->req, &r->rep, &err)) {
        print_error("%s request failed: %s\n", proto_type_name(r->req.type), err.message);
        fail();
    }
    if (record) {
        put_reply(&r->replies, &r->rep);
        r->n_replies++;
    }
}

/* Starts the participant on `input` in `outdir`, says hello and sends the interface. */
static void start(run *r, const char *input, const char *outdir)
{
    memset(r, 0, sizeof *r);
    char endpoint[256];
    r->pid = dem_test_start_participant(input, outdir, endpoint, sizeof endpoint);
    proto_options opt;
    proto_options_default(&opt);
    opt.timeout_ms = 120000;
    nc_error err;
    assert_int_equal(proto_peer_open(&r->peer, "dem", endpoint, &opt, &err), 0);
    assert_int_equal(proto_peer_hello(r->peer, &r->rep, &err), 0);
    assert_true(proto_has_capability(r->rep.text, "checkpoint"));
    double xyz[3 * NN];
    int32_t ids[NN], elements[2 * N_EDGES];
    net_mesh(xyz, ids, elements);
    proto_message_init(&r->req, PROTO_MSG_INTERFACE);
    assert_int_equal(proto_message_add_i32(&r->req, "node_ids", ids, NN, 0, &err), 0);
    assert_int_equal(proto_message_add_f64(&r->req, "coordinates", xyz, NN, 3, &err), 0);
    assert_int_equal(proto_message_add_i32(&r->req, "elements", elements, N_EDGES, 2, &err), 0);
    request(r, 0);
}

/* SHUTDOWN and the exit status of the participant. */
static int stop(run *r)
{
    proto_message_init(&r->req, PROTO_MSG_SHUTDOWN);
    request(r, 0);
    proto_message_free(&r->req);
    proto_message_free(&r->rep);
    proto_peer_close(r->peer);
    int status = 0;
    assert_int_equal(waitpid(r->pid, &status, 0), r->pid);
    assert_true(WIFEXITED(status));
    return WEXITSTATUS(status);
}

static void command(run *r, proto_msg_type type, long step, const char *name)
{
    proto_message_init(&r->req, type);
    r->req.step = step;
    r->req.time_s = (double)step * DT_S;
    if (name) snprintf(r->req.text, sizeof r->req.text, "%s", name);
}

static void checkpoint_name(int step, char *out, size_t size)
{
    snprintf(out, size, "step_%06d", step);
}

/* Steps from..to-1 as a strong coupler; a checkpoint after every step in checkpoint_steps. */
static void run_steps(run *r, int from, int to)
{
    nc_error err;
    for (int step = from; step < to; step++) {
        int rec = step >= K_RESUME;
        double t = (double)step * DT_S;
        command(r, PROTO_MSG_BEGIN_STEP, step, NULL);
        r->req.dt_s = DT_S;
        request(r, rec);
        int iterations = 1 + (step % 3 == 1) + (step % 4 == 2);
        double x[3 * NN], v[3 * NN];
        memcpy(x, r->u, sizeof x);
        for (int it = 1; it <= iterations; it++) {
            for (int k = 0; k < 3 * NN; k++) v[k] = (x[k] - r->u[k]) / DT_S;
            proto_message_init(&r->req, PROTO_MSG_SOLVE);
            r->req.step = step;
            r->req.iteration = it;
            r->req.time_s = t;
            r->req.dt_s = DT_S;
            assert_int_equal(proto_message_add_f64(&r->req, "displacement", x, NN, 3, &err), 0);
            assert_int_equal(proto_message_add_f64(&r->req, "velocity", v, NN, 3, &err), 0);
            int jacobian = it > 1 || step % 2 == 0;
            if (jacobian) assert_int_equal(proto_message_set_value(&r->req, "jacobian", 1.0, &err), 0);
            request(r, rec);
            r->solves_with_jacobian += jacobian;
            const double *f;
            assert_int_equal(proto_message_get_f64(&r->rep, "force", NN, 3, &f, NULL, &err), 0);
            if (step == K_RESUME - 1) r->contacts_at_resume = proto_message_value(&r->rep, "contacts", -1);
            /* the stand-in structure: the next input half-way to its static answer */
            if (it < iterations)
                for (int k = 0; k < 3 * NN; k++) x[k] = 0.5 * (x[k] + COMPLIANCE_M_PER_N * f[k]);
        }
        memcpy(r->u, x, sizeof x);
        command(r, PROTO_MSG_ACCEPT_STEP, step, NULL);
        r->req.dt_s = DT_S;
        request(r, rec);
        for (size_t c = 0; c < sizeof checkpoint_steps / sizeof *checkpoint_steps; c++)
            if (checkpoint_steps[c] == step + 1) {
                char name[64];
                checkpoint_name(step + 1, name, sizeof name);
                command(r, PROTO_MSG_CHECKPOINT, step + 1, name);
                request(r, step + 1 > K_RESUME);
                if (step + 1 == K_RESUME) memcpy(r->u_at_resume, r->u, sizeof r->u);
            }
    }
}

/* A command that must be refused; returns the reason in msg. */
static void refused(run *r, proto_msg_type type, long step, const char *name, char *msg, size_t size)
{
    nc_error err;
    command(r, type, step, name);
    assert_int_equal(proto_peer_request(r->peer, &r->req, &r->rep, &err), -1);
    assert_int_equal(err.code, PROTO_ERR_PEER);
    snprintf(msg, size, "%s", err.message);
    print_message("refused as expected: %s\n", msg);
}

/* ---- result files ---------------------------------------------------------------------------- */

typedef struct dataset {
    char name[256];
    int rank;
    hsize_t dims[4];
    blob bytes;
} dataset;

typedef struct results {
    dataset d[64];
    int n;
} results;

static herr_t visit(hid_t group, const char *name, const H5L_info_t *info, void *data)
{
    (void)info;
    results *r = data;
    hid_t d = H5Dopen2(group, name, H5P_DEFAULT);
    if (d < 0) return 0; /* a group */
    assert_true(r->n < 64);
    dataset *x = &r->d[r->n++];
    memset(x, 0, sizeof *x);
    snprintf(x->name, sizeof x->name, "%s", name);
    hid_t space = H5Dget_space(d), type = H5Dget_type(d);
    x->rank = H5Sget_simple_extent_ndims(space);
    H5Sget_simple_extent_dims(space, x->dims, NULL);
    size_t bytes = (size_t)H5Sget_simple_extent_npoints(space) * H5Tget_size(type);
    if (bytes) {
        unsigned char *buf = malloc(bytes);
        assert_non_null(buf);
        assert_true(H5Dread(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) >= 0);
        put(&x->bytes, buf, bytes);
        free(buf);
    }
    H5Tclose(type);
    H5Sclose(space);
    H5Dclose(d);
    return 0;
}

static void read_results(const char *h5, results *r)
{
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    memset(r, 0, sizeof *r);
    hid_t f = H5Fopen(h5, H5F_ACC_RDONLY, H5P_DEFAULT);
    assert_true(f >= 0);
    assert_true(H5Lvisit(f, H5_INDEX_NAME, H5_ITER_INC, visit, r) >= 0);
    H5Fclose(f);
}

static void free_results(results *r)
{
    for (int k = 0; k < r->n; k++) free(r->d[k].bytes.data);
    r->n = 0;
}

static hsize_t rows_of(const results *r, const char *name)
{
    for (int k = 0; k < r->n; k++)
        if (strcmp(r->d[k].name, name) == 0) return r->d[k].dims[0];
    return 0;
}

static void assert_same_results(const results *a, const results *b)
{
    assert_int_equal(a->n, b->n);
    for (int k = 0; k < a->n; k++) {
        const dataset *x = &a->d[k], *y = &b->d[k];
        assert_string_equal(x->name, y->name);
        assert_int_equal(x->rank, y->rank);
        for (int q = 0; q < x->rank; q++)
            if (x->dims[q] != y->dims[q]) {
                print_error("%s: dimension %d: %llu rows uninterrupted, %llu resumed\n", x->name,
                            q, (unsigned long long)x->dims[q], (unsigned long long)y->dims[q]);
                fail();
            }
        assert_int_equal(x->bytes.len, y->bytes.len);
        if (x->bytes.len && memcmp(x->bytes.data, y->bytes.data, x->bytes.len) != 0) {
            print_error("%s differs between the uninterrupted and the resumed run\n", x->name);
            fail();
        }
    }
}

static char *read_text(const char *path)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    blob b = {0};
    char chunk[4096];
    size_t n;
    while ((n = fread(chunk, 1, sizeof chunk, f)) > 0) put(&b, chunk, n);
    fclose(f);
    put(&b, "", 1);
    return (char *)b.data;
}

static int exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

/* Net contacts with tangential spring history in a checkpoint, and contacts of cluster spheres. */
static void count_history(const char *ck, int first_cluster_sphere, int *net_with_ft, int *cluster)
{
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    hid_t f = H5Fopen(ck, H5F_ACC_RDONLY, H5P_DEFAULT);
    assert_true(f >= 0);
    hid_t dk = H5Dopen2(f, "/contacts/kind", H5P_DEFAULT), di = H5Dopen2(f, "/contacts/sphere", H5P_DEFAULT);
    hid_t df = H5Dopen2(f, "/contacts/tangential_force", H5P_DEFAULT);
    assert_true(dk >= 0 && di >= 0 && df >= 0);
    hid_t space = H5Dget_space(dk);
    hsize_t n = 0;
    H5Sget_simple_extent_dims(space, &n, NULL);
    H5Sclose(space);
    int32_t *kind = malloc((n + 1) * sizeof *kind), *sph = malloc((n + 1) * sizeof *sph);
    double *ft = malloc((3 * n + 1) * sizeof *ft);
    assert_true(n == 0 || (H5Dread(dk, H5T_NATIVE_INT32, H5S_ALL, H5S_ALL, H5P_DEFAULT, kind) >= 0 &&
                           H5Dread(di, H5T_NATIVE_INT32, H5S_ALL, H5S_ALL, H5P_DEFAULT, sph) >= 0 &&
                           H5Dread(df, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, ft) >= 0));
    *net_with_ft = *cluster = 0;
    for (hsize_t c = 0; c < n; c++) {
        double t2 = ft[3 * c] * ft[3 * c] + ft[3 * c + 1] * ft[3 * c + 1] + ft[3 * c + 2] * ft[3 * c + 2];
        *net_with_ft += (kind[c] == 3 || kind[c] == 4) && t2 > 0.0;
        *cluster += sph[c] >= first_cluster_sphere;
    }
    free(kind);
    free(sph);
    free(ft);
    H5Dclose(dk);
    H5Dclose(di);
    H5Dclose(df);
    H5Fclose(f);
}

/* ---- the test ---------------------------------------------------------------------------------- */

static void write_input(const char *path, const char *extra_particles)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f, model_json, extra_particles);
    fclose(f);
}

static void test_resume_is_bit_identical(void **state)
{
    (void)state;
    const char *bin = getenv("NC_BIN");
    if (!bin || !bin[0]) {
        print_message("NC_BIN not set: skipped\n");
        skip();
    }
    const char *tmp = getenv("NC_TMP");
    if (!tmp || !tmp[0]) tmp = "/tmp";
    char dir[512], input[600], other[600], out[600], h5[700], ck_dir[700], path[800];
    snprintf(dir, sizeof dir, "%s/dem_checkpoint.%ld", tmp, (long)getpid());
    nc_error err;
    assert_int_equal(nc_file_make_dirs(dir, &err), 0);
    snprintf(input, sizeof input, "%s/dem.json", dir);
    snprintf(other, sizeof other, "%s/dem_other.json", dir);
    snprintf(out, sizeof out, "%s/out", dir);
    snprintf(h5, sizeof h5, "%s/dem.h5", out);
    snprintf(ck_dir, sizeof ck_dir, "%s/checkpoint", out);
    write_input(input, "");
    /* another model: one more rock beside the net */
    write_input(other, ", {\"position\": [3.5, 0.5, 1.0], \"radius\": 0.3}");
    assert_int_equal(nc_file_make_dirs(out, &err), 0);

    /* A: the run never interrupted */
    run a;
    start(&a, input, out);
    assert_false(exists(h5)); /* nothing written before the first BEGIN_STEP */
    run_steps(&a, 0, N_STEPS);
    assert_int_equal(stop(&a), 0);
    print_message("uninterrupted: %ld replies from step %d, %ld solves with the Jacobian, %g net "
                  "contacts at the checkpoint\n", a.n_replies, K_RESUME, a.solves_with_jacobian,
                  a.contacts_at_resume);
    assert_true(a.contacts_at_resume >= 2); /* rock and cluster on the net */
    /* two newest checkpoints kept */
    snprintf(path, sizeof path, "%s/dem_step_000004.h5", ck_dir);
    assert_false(exists(path));
    snprintf(path, sizeof path, "%s/dem_step_000014.h5", ck_dir);
    assert_true(exists(path));
    char ck[800];
    snprintf(ck, sizeof ck, "%s/dem_step_%06d.h5", ck_dir, K_RESUME);
    assert_true(exists(ck));
    int net_ft = 0, cluster = 0;
    count_history(ck, 1, &net_ft, &cluster);
    print_message("checkpoint at step %d: %d net contacts with tangential history, %d contacts of "
                  "cluster spheres\n", K_RESUME, net_ft, cluster);
    assert_true(net_ft >= 2);
    assert_true(cluster >= 1);

    results ra, rc;
    read_results(h5, &ra);
    hsize_t rows = rows_of(&ra, "time");
    print_message("uninterrupted dem.h5: %d datasets, %llu output steps\n", ra.n, (unsigned long long)rows);
    assert_int_equal(rows, 1 + N_STEPS / 4); /* t = 0 and every 8e-4 s */
    char xp[700], xn[700];
    snprintf(xp, sizeof xp, "%s/particles.xdmf", out);
    snprintf(xn, sizeof xn, "%s/dem_net.xdmf", out);
    char *xdmf_particles = read_text(xp), *xdmf_net = read_text(xn);

    /* killed right after the checkpoint at K_RESUME: the rows it counts are in dem.h5 (written
     * for the checkpoint; else only the first output step's would be, the rest in memory) */
    {
        char out_k[600], h5_k[700];
        snprintf(out_k, sizeof out_k, "%s/out_killed", dir);
        snprintf(h5_k, sizeof h5_k, "%s/dem.h5", out_k);
        assert_int_equal(nc_file_make_dirs(out_k, &err), 0);
        run k;
        start(&k, input, out_k);
        run_steps(&k, 0, K_RESUME);
        kill(k.pid, SIGKILL);
        int status = 0;
        assert_int_equal(waitpid(k.pid, &status, 0), k.pid);
        proto_message_free(&k.req);
        proto_message_free(&k.rep);
        proto_peer_close(k.peer);
        free(k.replies.data);
        results rk;
        read_results(h5_k, &rk);
        assert_int_equal(rows_of(&rk, "time"), 1 + K_RESUME / 4);   /* t = 0 and every 8e-4 s */
        free_results(&rk);
    }

    /* refused resumes: missing, another step, another model; the results stay as they are */
    char msg[1024];
    run c;
    start(&c, input, out);
    refused(&c, PROTO_MSG_RESUME, 7, "step_000007", msg, sizeof msg);
    assert_non_null(strstr(msg, "checkpoint/dem_step_000007.h5"));
    refused(&c, PROTO_MSG_RESUME, K_RESUME + 1, "step_000009", msg, sizeof msg);
    assert_non_null(strstr(msg, "dem_step_000009.h5"));
    assert_non_null(strstr(msg, "step 9"));
    refused(&c, PROTO_MSG_RESUME, K_RESUME, "../dem", msg, sizeof msg);
    assert_non_null(strstr(msg, "only letters"));
    assert_int_equal(stop(&c), 1);
    run d;
    start(&d, other, out);
    refused(&d, PROTO_MSG_RESUME, K_RESUME, "step_000009", msg, sizeof msg);
    assert_non_null(strstr(msg, "dem_step_000009.h5"));
    assert_non_null(strstr(msg, "another model: spheres 4 in the checkpoint, 5 in this model"));
    assert_int_equal(stop(&d), 1);
    read_results(h5, &rc);
    assert_same_results(&ra, &rc);
    free_results(&rc);

    /* B: a fresh process resumes at K_RESUME and gets the same commands */
    run b;
    start(&b, input, out);
    command(&b, PROTO_MSG_RESUME, K_RESUME, "step_000009");
    request(&b, 0);
    memcpy(b.u, a.u_at_resume, sizeof b.u);
    run_steps(&b, K_RESUME, N_STEPS);
    assert_int_equal(stop(&b), 0);
    print_message("resumed: %ld replies\n", b.n_replies);
    assert_int_equal(b.n_replies, a.n_replies);
    assert_int_equal(b.replies.len, a.replies.len);
    assert_memory_equal(b.replies.data, a.replies.data, a.replies.len);
    read_results(h5, &rc);
    assert_same_results(&ra, &rc);
    char *xp_b = read_text(xp), *xn_b = read_text(xn);
    assert_string_equal(xp_b, xdmf_particles);
    assert_string_equal(xn_b, xdmf_net);
    /* the resumed run keeps its checkpoint and the newest */
    assert_true(exists(ck));
    assert_true(exists(path));
    free(xp_b);
    free(xn_b);
    free(xdmf_particles);
    free(xdmf_net);
    free_results(&ra);
    free_results(&rc);
    free(a.replies.data);
    free(b.replies.data);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_resume_is_bit_identical),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
