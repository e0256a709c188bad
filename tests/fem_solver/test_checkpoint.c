/* test_checkpoint — checkpoint and resume of the FEM (protocol/README.md §3.3) are
 * bit-identical to a run that never stopped.
 *
 * Model: a 3 m x 3 m steel rope net, 7 x 7 nodes (E 1e11 Pa, 12 mm rope, 5 kN pretension,
 * self-weight ramped over 5 ms, Rayleigh tau 5 /s), edges fixed; a rock's contact forces of
 * 30-60 kN on the centre node and its neighbours, some steps with the contact's
 * interface Jacobian between the centre node and a diagonal neighbour (a node pair that
 * shares no element: the sparse pattern grows), three SOLVEs per step (the second with
 * another force: every further SOLVE restores the start of the step).
 *
 * - In-process (fem_checkpoint API): a checkpoint after the pattern grew, loaded into a fresh
 *   analysis, gives the same pattern and the same states of every later step, bit for bit.
 * - Over the protocol (the real program, $NC_BIN/fem_solver): run A goes through 16 steps
 *   with CHECKPOINTs before steps 4, 7 and 10. Run A' does the same in another folder and is
 *   killed after step 8 (its fem.h5 then holds rows beyond the checkpoint of step 7); run B,
 *   a fresh process in that folder, RESUMEs step 7 and gets the same commands as A: every
 *   reply (arrays and values) equals A's byte for byte, fem.h5 holds exactly A's series
 *   (same rows, same bytes, same max |u|) and fem.xdmf is A's; only the two newest
 *   checkpoints remain.
 * - Element history: the barrier support rope of fem_solver/examples/barrier_rope_brake.json
 *   (a sliding rope anchored through two brakes), checkpointed while its brakes yield: the
 *   resumed run's states and brake strokes and dissipated energies equal the uninterrupted
 *   run's bit for bit.
 * - Errors: RESUME of a missing checkpoint names the file; of another step names the step;
 *   of another model's checkpoint names what differs (node count; same counts but other
 *   E); CHECKPOINT inside a step and RESUME after the first step are refused while the
 *   solver keeps serving, and a failed RESUME leaves the fresh state (the next step's reply
 *   equals run A's).
 */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>
#include "../nc_test_assert.h"

#include <hdf5.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "../../fem_solver/fem_analysis.h"
#include "../../fem_solver/fem_checkpoint.h"
#include "../../fem_solver/fem_input.h"
#include "../../fem_solver/fem_output.h"
#include "fem_test_util.h"
#include "nc_file.h"
#include "proto.h"

#define N_STEPS 16
#define K_RESUME 7
#define N_IT 3
#define DT 1e-3
#define CENTRE 24      /* node (3, 3) of the 7 x 7 net */
#define DIAGONAL 32    /* node (4, 4): no element joins it to the centre */

/* 12 mm six-strand rope: A = 0.58 pi d^2 / 4 = 6.56e-5 m^2; 5 kN pretension */
static const char *net_json_fmt =
    "{\"net\": {\"origin_m\": [0, 0, 0], \"edge1_m\": [3, 0, 0], \"edge2_m\": [0, 3, 0],\n"
    "         \"count1\": %d, \"count2\": %d},\n"
    " \"element_sets\": [{\"name\": \"rope\", \"youngs_modulus_pa\": %g, \"diameter_m\": 0.012,\n"
    "   \"density_kg_m3\": 7850, \"pretension_n\": 5000}],\n"
    " \"supports\": [{\"nodes\": \"boundary\"}], \"self_weight\": true,\n"
    " \"rayleigh\": {\"tau_per_s\": 5}, \"monitor_nodes\": [\"center\"],\n"
    " \"output\": {\"interval_steps\": 3},\n"
    " \"analysis\": {\"type\": \"dynamic\", \"dt_s\": 0.001, \"load_ramp_s\": 0.005}}\n";

static const char *net_json(const char *name, int count, double E)
{
    char text[2048];
    snprintf(text, sizeof text, net_json_fmt, count, count, E);
    return fem_test_write(name, text);
}

/* The contact force of (step, iteration) on the model nodes [3 n_nodes]: 30 kN rising by
 * 2 kN per step on the centre, 5 kN on its four neighbours, 10 kN on the diagonal node;
 * iteration 2 pushes 30 % harder (a not yet converged interface iteration). */
static void contact_force(int step, int it, int nx, double *f)
{
    memset(f, 0, 3 * (size_t)nx * nx * sizeof *f);
    double scale = it == 2 ? 1.3 : 1.0;
    f[3 * CENTRE + 2] = -(3e4 + 2e3 * step) * scale;
    const int nb[4] = {CENTRE - 1, CENTRE + 1, CENTRE - nx, CENTRE + nx};
    for (int i = 0; i < 4; i++) f[3 * nb[i] + 2] = -5e3 * scale;
    f[3 * DIAGONAL + 2] = -1e4 * scale;
}

/* steps with the contact's interface Jacobian (pattern growth at the first) */
static int jacobian_step(int step)
{
    return step == 2 || step == 3 || step == 5 || step == 8 || step == 9 || step == 12;
}

/* The rock on the centre and the diagonal node: K = k w w^T in z, w = (1/2, 1/2). */
static const double K_CONTACT_N_M = 2e6;
static void contact_blocks(int *nodes, double *K, double *C)
{
    const int pair[4][2] = {{CENTRE, CENTRE}, {CENTRE, DIAGONAL}, {DIAGONAL, CENTRE}, {DIAGONAL, DIAGONAL}};
    memset(K, 0, 36 * sizeof *K);
    memset(C, 0, 36 * sizeof *C);
    for (int b = 0; b < 4; b++) {
        nodes[2 * b] = pair[b][0];
        nodes[2 * b + 1] = pair[b][1];
        K[9 * b + 8] = 0.25 * K_CONTACT_N_M;
        C[9 * b + 8] = 0.25 * 2e3;   /* a contact dashpot, N s/m */
    }
}

static void out_dir(const char *tag, char *dir, size_t size)
{
    const char *tmp = getenv("NC_TMP");
    if (!tmp || !*tmp) tmp = "/tmp";
    snprintf(dir, size, "%s/%d-ck-%s", tmp, (int)getpid(), tag);
    nc_error err;
    assert_int_equal(nc_file_make_dirs(dir, &err), 0);
}

/* ---- in-process --------------------------------------------------------------------- */

/* One coupled step as fem_coupled.c runs it: save, N_IT solves (restoring before each
 * further one), the linearisation about the previous solve's state on Jacobian steps. */
static void step_in_process(fem_analysis *s, const fem_model *m, int k, double *u_k, double *v_k)
{
    nc_error err;
    s->cur.time_s = k * DT;
    assert_int_equal(fem_analysis_save(s, &err), 0);
    int nodes[8];
    double K[36], C[36];
    contact_blocks(nodes, K, C);
    for (int it = 1; it <= N_IT; it++) {
        if (it > 1) assert_int_equal(fem_analysis_restore(s, &err), 0);
        contact_force(k, it, 7, s->f_coupling);
        if (jacobian_step(k)) {
            if (fem_analysis_set_linearisation(s, u_k, v_k, 4, nodes, K, C, &err))
                fail_msg("%s", err.message);
        } else {
            fem_analysis_clear_linearisation(s);
        }
        if (fem_analysis_step(s, DT, &err)) fail_msg("step %d: %s", k, err.message);
        memcpy(u_k, s->cur.u, (size_t)s->ndof * sizeof *u_k);
        memcpy(v_k, s->cur.v, (size_t)s->ndof * sizeof *v_k);
    }
    (void)m;
}

static void test_in_process_resume(void **state)
{
    (void)state;
    nc_error err;
    fem_model m;
    if (fem_input_load(net_json("ck_net.json", 7, 1e11), &m, &err)) fail_msg("%s", err.message);
    assert_int_equal(m.n_nodes, 49);
    char dir[600];
    out_dir("unit", dir, sizeof dir);
    size_t nd = 3 * (size_t)m.n_nodes;
    double *u_k = calloc(nd, sizeof *u_k), *v_k = calloc(nd, sizeof *v_k);
    double *ref_u = malloc(N_STEPS * nd * sizeof *ref_u), *ref_v = malloc(N_STEPS * nd * sizeof *ref_v);
    double *uk_at = malloc(nd * sizeof *uk_at), *vk_at = malloc(nd * sizeof *vk_at);
    assert_non_null(ref_u);
    fem_analysis a;
    fem_output oa;
    memset(&oa, 0, sizeof oa);
    oa.max_u_node = -1;
    assert_int_equal(fem_analysis_init(&a, &m, &err), 0);
    assert_int_equal(fem_analysis_initial_acceleration(&a, &err), 0);
    int nnz0 = a.K.nnz, nnz_at = 0;
    for (int k = 0; k < N_STEPS; k++) {
        if (k == K_RESUME) {
            if (fem_checkpoint_save(dir, "unit", k, k * DT, &a, &oa, NULL, &err)) fail_msg("%s", err.message);
            memcpy(uk_at, u_k, nd * sizeof *u_k);
            memcpy(vk_at, v_k, nd * sizeof *v_k);
            nnz_at = a.K.nnz;
        }
        step_in_process(&a, &m, k, u_k, v_k);
        memcpy(ref_u + k * nd, a.cur.u, nd * sizeof *ref_u);
        memcpy(ref_v + k * nd, a.cur.v, nd * sizeof *ref_v);
    }
    /* the pattern grew by the centre-diagonal pair before the checkpoint, and kept
     * factorisations were reused (modified Newton) */
    assert_int_equal(a.stats.pattern_growths, 1);
    assert_true(nnz_at > nnz0);
    assert_true(a.stats.pcg_solves > 0);
    assert_below(ref_u[(N_STEPS - 1) * nd + 3 * CENTRE + 2], -0.01);   /* the rock pushed the net down */

    fem_analysis b;
    fem_output ob;
    memset(&ob, 0, sizeof ob);
    ob.max_u_node = -1;
    assert_int_equal(fem_analysis_init(&b, &m, &err), 0);
    assert_int_equal(fem_analysis_initial_acceleration(&b, &err), 0);
    if (fem_checkpoint_load(dir, "unit", K_RESUME, K_RESUME * DT, &b, &ob, NULL, &err))
        fail_msg("%s", err.message);
    assert_int_equal(b.K.nnz, nnz_at);
    assert_int_equal(b.n_pairs, 1);
    assert_int_equal(b.stats.pattern_growths, 1);
    memcpy(u_k, uk_at, nd * sizeof *u_k);
    memcpy(v_k, vk_at, nd * sizeof *v_k);
    for (int k = K_RESUME; k < N_STEPS; k++) {
        step_in_process(&b, &m, k, u_k, v_k);
        assert_memory_equal(b.cur.u, ref_u + k * nd, nd * sizeof *ref_u);
        assert_memory_equal(b.cur.v, ref_v + k * nd, nd * sizeof *ref_v);
    }
    assert_int_equal(b.stats.factorizations, a.stats.factorizations);
    assert_int_equal(b.stats.pcg_iterations, a.stats.pcg_iterations);
    assert_int_equal(b.stats.assemblies, a.stats.assemblies);
    fem_analysis_free(&a);
    fem_analysis_free(&b);
    fem_output_close(&oa);
    fem_output_close(&ob);
    free(u_k); free(v_k); free(ref_u); free(ref_v); free(uk_at); free(vk_at);
    fem_model_free(&m);
}

/* The brakes of the barrier rope example yield during the load ramp (0.5 s) and its
 * overshoot: at the checkpoint (0.3 s) their stroke is 0.16 m, at 0.7 s 0.52 m. */
static void test_in_process_resume_brakes(void **state)
{
    (void)state;
    enum { K_CK = 300, K_END = 700 };
    nc_error err;
    fem_model m;
    if (fem_input_load("fem_solver/examples/barrier_rope_brake.json", &m, &err)) fail_msg("%s", err.message);
    assert_true(m.history_count > 0);
    const double dt = m.settings.dt_s;
    char dir[600];
    out_dir("brake", dir, sizeof dir);
    size_t nd = 3 * (size_t)m.n_nodes, nh = (size_t)m.history_count;
    double *ref_u = malloc(nd * sizeof *ref_u), *ref_h = malloc(nh * sizeof *ref_h);
    double *stroke = calloc((size_t)m.n_elements, sizeof *stroke),
           *dissipated = calloc((size_t)m.n_elements, sizeof *dissipated);
    double stroke_at_ck = 0.0, stroke_end = 0.0;
    assert_non_null(ref_u);
    fem_analysis a, b;
    fem_output oa, ob;
    memset(&oa, 0, sizeof oa);
    memset(&ob, 0, sizeof ob);
    oa.max_u_node = ob.max_u_node = -1;
    assert_int_equal(fem_analysis_init(&a, &m, &err), 0);
    assert_int_equal(fem_analysis_initial_acceleration(&a, &err), 0);
    for (int k = 1; k <= K_END; k++) {
        if (k == K_CK + 1) {
            if (fem_checkpoint_save(dir, "brake", K_CK, K_CK * dt, &a, &oa, NULL, &err))
                fail_msg("%s", err.message);
            fem_analysis_element_history_output(&a, stroke, dissipated);
            for (int e = 0; e < m.n_elements; e++) stroke_at_ck = fmax(stroke_at_ck, stroke[e]);
        }
        if (fem_analysis_step(&a, dt, &err)) fail_msg("step %d: %s", k, err.message);
        a.cur.time_s = k * dt;
    }
    fem_analysis_element_history_output(&a, stroke, dissipated);
    for (int e = 0; e < m.n_elements; e++) stroke_end = fmax(stroke_end, stroke[e]);
    /* yielding before the checkpoint and after it: the history matters */
    assert_true(stroke_at_ck > 0.1);
    assert_true(stroke_end > stroke_at_ck + 0.2);
    memcpy(ref_u, a.cur.u, nd * sizeof *ref_u);
    memcpy(ref_h, a.cur.element_history, nh * sizeof *ref_h);

    assert_int_equal(fem_analysis_init(&b, &m, &err), 0);
    assert_int_equal(fem_analysis_initial_acceleration(&b, &err), 0);
    if (fem_checkpoint_load(dir, "brake", K_CK, K_CK * dt, &b, &ob, NULL, &err))
        fail_msg("%s", err.message);
    for (int k = K_CK + 1; k <= K_END; k++) {
        if (fem_analysis_step(&b, dt, &err)) fail_msg("resumed step %d: %s", k, err.message);
        b.cur.time_s = k * dt;
    }
    assert_memory_equal(b.cur.u, ref_u, nd * sizeof *ref_u);
    assert_memory_equal(b.cur.element_history, ref_h, nh * sizeof *ref_h);
    fem_analysis_free(&a);
    fem_analysis_free(&b);
    fem_output_close(&oa);
    fem_output_close(&ob);
    free(ref_u); free(ref_h); free(stroke); free(dissipated);
    fem_model_free(&m);
}

/* ---- over the protocol ---------------------------------------------------------------- */

typedef struct reply_rec {
    unsigned char *bytes;     /* displacement, velocity, then every value (name, number) */
    size_t size;
} reply_rec;

typedef struct session {
    pid_t pid;
    proto_peer *peer;
    proto_message req, rep;
    int n;                    /* interface nodes */
    int32_t ids[128];          /* model node of each interface node */
    int iface_of[128];         /* interface index of each model node */
} session;

static void open_session(session *ss, const char *json, const char *dir, const char *tag)
{
    char epfile[700], ep[256];
    snprintf(epfile, sizeof epfile, "%s/%s.endpoint", dir, tag);
    memset(ss, 0, sizeof *ss);
    ss->pid = fem_test_spawn(json, dir, epfile, "60");
    assert_true(ss->pid > 0);
    if (fem_test_read_endpoint(epfile, ep, sizeof ep)) {
        kill(ss->pid, SIGKILL);
        fail_msg("fem_solver did not write its endpoint file %s", epfile);
    }
    nc_error err;
    proto_options opt;
    proto_options_default(&opt);
    opt.timeout_ms = 60000;
    assert_int_equal(proto_peer_open(&ss->peer, "fem", ep, &opt, &err), 0);
    if (proto_peer_hello(ss->peer, &ss->rep, &err)) fail_msg("%s", err.message);
    assert_non_null(strstr(ss->rep.text, "checkpoint"));
    proto_message_init(&ss->req, PROTO_MSG_INTERFACE);
    if (proto_peer_request(ss->peer, &ss->req, &ss->rep, &err)) fail_msg("%s", err.message);
    const int32_t *ids;
    size_t n = 0;
    assert_int_equal(proto_message_get_i32(&ss->rep, "node_ids", 0, 0, &ids, &n, &err), 0);
    assert_true(n <= 128);
    ss->n = (int)n;
    for (int i = 0; i < 128; i++) ss->iface_of[i] = -1;
    for (size_t i = 0; i < n; i++) {
        ss->ids[i] = ids[i];
        if (ids[i] >= 0 && ids[i] < 128) ss->iface_of[ids[i]] = (int)i;
    }
}

static int close_session(session *ss)
{
    nc_error err;
    proto_message_init(&ss->req, PROTO_MSG_SHUTDOWN);
    if (proto_peer_request(ss->peer, &ss->req, &ss->rep, &err)) fail_msg("shutdown: %s", err.message);
    int code = fem_test_wait_exit(ss->pid, 60);
    proto_message_free(&ss->req);
    proto_message_free(&ss->rep);
    proto_peer_close(ss->peer);
    return code;
}

static void kill_session(session *ss)
{
    kill(ss->pid, SIGKILL);
    fem_test_wait_exit(ss->pid, 30);
    proto_message_free(&ss->req);
    proto_message_free(&ss->rep);
    proto_peer_close(ss->peer);
}

/* A command without arrays; returns the request's result (error text in err). */
static int command(session *ss, proto_msg_type type, long step, double time_s, const char *text,
                   nc_error *err)
{
    proto_message_init(&ss->req, type);
    ss->req.step = step;
    ss->req.time_s = time_s;
    ss->req.dt_s = DT;
    if (text) snprintf(ss->req.text, sizeof ss->req.text, "%s", text);
    return proto_peer_request(ss->peer, &ss->req, &ss->rep, err);
}

static void record(reply_rec *r, const proto_message *rep, int n)
{
    nc_error err;
    const double *u, *v;
    assert_int_equal(proto_message_get_f64(rep, "displacement", (size_t)n, 3, &u, NULL, &err), 0);
    assert_int_equal(proto_message_get_f64(rep, "velocity", (size_t)n, 3, &v, NULL, &err), 0);
    size_t arrays = 2 * 3 * (size_t)n * sizeof(double);
    size_t values = rep->n_values * (sizeof rep->values[0].name + sizeof(double));
    r->size = arrays + values;
    r->bytes = calloc(1, r->size);
    memcpy(r->bytes, u, arrays / 2);
    memcpy(r->bytes + arrays / 2, v, arrays / 2);
    unsigned char *p = r->bytes + arrays;
    for (size_t i = 0; i < rep->n_values; i++) {
        memcpy(p, rep->values[i].name, sizeof rep->values[i].name);
        memcpy(p + sizeof rep->values[i].name, &rep->values[i].value, sizeof(double));
        p += sizeof rep->values[i].name + sizeof(double);
    }
    assert_true(rep->n_values >= 10);   /* newton_iterations, residual_norm, the energy terms */
}

/* The coupler's side of steps [from, to): BEGIN_STEP, N_IT SOLVEs (the Jacobian about the
 * previous SOLVE's reply on Jacobian steps), ACCEPT_STEP, and a CHECKPOINT before steps 4, 7
 * and 10. u_k, v_k [3 n] carry the interface state between steps (a resumed coupler has it
 * from its own checkpoint). */
static void run_steps(session *ss, int from, int to, reply_rec recs[][N_IT], double *u_k,
                      double *v_k)
{
    nc_error err;
    int n = ss->n;
    double *f_model = calloc(3 * 49, sizeof *f_model), *force = calloc(3 * (size_t)n, sizeof *force);
    int32_t jn[8];
    int mn[8];
    double K[36], C[36];
    contact_blocks(mn, K, C);
    for (int b = 0; b < 8; b++) jn[b] = ss->iface_of[mn[b]];
    for (int k = from; k < to; k++) {
        if (k == 4 || k == 7 || k == 10) {
            char name[32];
            snprintf(name, sizeof name, "step_%06d", k);
            if (command(ss, PROTO_MSG_CHECKPOINT, k, k * DT, name, &err))
                fail_msg("checkpoint %s: %s", name, err.message);
        }
        if (command(ss, PROTO_MSG_BEGIN_STEP, k, k * DT, NULL, &err)) fail_msg("%s", err.message);
        for (int it = 1; it <= N_IT; it++) {
            contact_force(k, it, 7, f_model);
            for (int i = 0; i < n; i++)
                for (int d = 0; d < 3; d++) force[3 * i + d] = f_model[3 * ss->ids[i] + d];
            proto_message_init(&ss->req, PROTO_MSG_SOLVE);
            ss->req.step = k;
            ss->req.iteration = it;
            ss->req.time_s = k * DT;
            ss->req.dt_s = DT;
            assert_int_equal(proto_message_add_f64(&ss->req, "force", force, (size_t)n, 3, &err), 0);
            if (jacobian_step(k)) {
                assert_int_equal(proto_message_add_i32(&ss->req, "jacobian_nodes", jn, 4, 2, &err), 0);
                assert_int_equal(proto_message_add_f64(&ss->req, "jacobian_stiffness", K, 4, 9, &err), 0);
                assert_int_equal(proto_message_add_f64(&ss->req, "jacobian_damping", C, 4, 9, &err), 0);
                assert_int_equal(proto_message_add_f64(&ss->req, "jacobian_displacement", u_k, (size_t)n, 3, &err), 0);
                assert_int_equal(proto_message_add_f64(&ss->req, "jacobian_velocity", v_k, (size_t)n, 3, &err), 0);
            }
            if (proto_peer_request(ss->peer, &ss->req, &ss->rep, &err))
                fail_msg("step %d iteration %d: %s", k, it, err.message);
            record(&recs[k][it - 1], &ss->rep, n);
            const double *u, *v;
            assert_int_equal(proto_message_get_f64(&ss->rep, "displacement", (size_t)n, 3, &u, NULL, &err), 0);
            assert_int_equal(proto_message_get_f64(&ss->rep, "velocity", (size_t)n, 3, &v, NULL, &err), 0);
            memcpy(u_k, u, 3 * (size_t)n * sizeof *u_k);
            memcpy(v_k, v, 3 * (size_t)n * sizeof *v_k);
        }
        if (command(ss, PROTO_MSG_ACCEPT_STEP, k, k * DT, NULL, &err)) fail_msg("%s", err.message);
    }
    free(f_model);
    free(force);
}

/* Every dataset of a fem.h5 series, as bytes (native type), with its dims. */
typedef struct h5_blob {
    hsize_t dims[3];
    int rank;
    size_t bytes;
    unsigned char *data;
} h5_blob;

static void read_blob(const char *file, const char *name, h5_blob *b)
{
    memset(b, 0, sizeof *b);
    hid_t f = H5Fopen(file, H5F_ACC_RDONLY, H5P_DEFAULT);
    if (f < 0) fail_msg("%s: cannot open", file);
    hid_t d = H5Dopen2(f, name, H5P_DEFAULT);
    if (d < 0) fail_msg("%s: no %s", file, name);
    hid_t sp = H5Dget_space(d), ft = H5Dget_type(d);
    b->rank = H5Sget_simple_extent_ndims(sp);
    H5Sget_simple_extent_dims(sp, b->dims, NULL);
    hid_t mt = H5Tget_class(ft) == H5T_FLOAT ? H5T_NATIVE_DOUBLE : H5T_NATIVE_INT;
    size_t count = (size_t)H5Sget_simple_extent_npoints(sp);
    b->bytes = count * H5Tget_size(mt);
    b->data = malloc(b->bytes + 8);
    if (count && H5Dread(d, mt, H5S_ALL, H5S_ALL, H5P_DEFAULT, b->data) < 0) fail_msg("%s: %s: read failed", file, name);
    H5Tclose(ft);
    H5Sclose(sp);
    H5Dclose(d);
    H5Fclose(f);
}

static double read_attr(const char *file, const char *object, const char *name)
{
    hid_t f = H5Fopen(file, H5F_ACC_RDONLY, H5P_DEFAULT);
    hid_t a = H5Aopen_by_name(f, object, name, H5P_DEFAULT, H5P_DEFAULT);
    double v = NAN;
    if (a < 0 || H5Aread(a, H5T_NATIVE_DOUBLE, &v) < 0) fail_msg("%s: %s has no attribute %s", file, object, name);
    H5Aclose(a);
    H5Fclose(f);
    return v;
}

static long rows(const char *file, const char *name)
{
    h5_blob b;
    read_blob(file, name, &b);
    free(b.data);
    return (long)b.dims[0];
}

static char *slurp(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f) fail_msg("%s: cannot read", path);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *text = malloc((size_t)n + 1);
    assert_int_equal(fread(text, 1, (size_t)n, f), (size_t)n);
    fclose(f);
    *size = (size_t)n;
    return text;
}

static int exists(const char *dir, const char *name)
{
    char path[900];
    struct stat st;
    snprintf(path, sizeof path, "%s/%s", dir, name);
    return stat(path, &st) == 0;
}

static void free_recs(reply_rec recs[][N_IT])
{
    for (int k = 0; k < N_STEPS; k++)
        for (int it = 0; it < N_IT; it++) free(recs[k][it].bytes);
}

static void test_resume_bit_identical(void **state)
{
    (void)state;
    if (!getenv("NC_BIN")) skip();
    const char *json = net_json("ck_protocol.json", 7, 1e11);
    char dir_a[600], dir_b[600];
    out_dir("a", dir_a, sizeof dir_a);
    out_dir("b", dir_b, sizeof dir_b);
    static reply_rec ra[N_STEPS][N_IT], rx[N_STEPS][N_IT], rb[N_STEPS][N_IT];
    memset(ra, 0, sizeof ra);
    memset(rx, 0, sizeof rx);
    memset(rb, 0, sizeof rb);
    double u_k[3 * 64] = {0}, v_k[3 * 64] = {0}, u_at[3 * 64], v_at[3 * 64];

    /* A: uninterrupted, checkpoints before steps 4, 7, 10 */
    session ss;
    open_session(&ss, json, dir_a, "a");
    assert_int_equal(ss.n, 49);
    run_steps(&ss, 0, K_RESUME, ra, u_k, v_k);
    memcpy(u_at, u_k, sizeof u_at);
    memcpy(v_at, v_k, sizeof v_at);
    run_steps(&ss, K_RESUME, N_STEPS, ra, u_k, v_k);
    assert_int_equal(close_session(&ss), 0);

    /* A': the same in dir_b, killed after step 8 (fem.h5 holds rows past the checkpoint: the
     * pause makes the output step at 9 ms write the rows waiting in memory, nc_h5_flush_due) */
    memset(u_k, 0, sizeof u_k);
    memset(v_k, 0, sizeof v_k);
    open_session(&ss, json, dir_b, "x");
    run_steps(&ss, 0, 8, rx, u_k, v_k);
    usleep((useconds_t)(NC_H5_FLUSH_INTERVAL_S * 1.2e6));
    run_steps(&ss, 8, 9, rx, u_k, v_k);
    kill_session(&ss);
    for (int k = 0; k < 9; k++)
        for (int it = 0; it < N_IT; it++) {
            assert_int_equal(rx[k][it].size, ra[k][it].size);
            assert_memory_equal(rx[k][it].bytes, ra[k][it].bytes, ra[k][it].size);
        }
    char h5_a[700], h5_b[700], ck_b[700], ck_a[700];
    snprintf(h5_a, sizeof h5_a, "%s/fem.h5", dir_a);
    snprintf(h5_b, sizeof h5_b, "%s/fem.h5", dir_b);
    snprintf(ck_a, sizeof ck_a, "%s/checkpoint", dir_a);
    snprintf(ck_b, sizeof ck_b, "%s/checkpoint", dir_b);
    assert_int_equal(rows(h5_b, "/monitor/time"), 10);   /* t = 0 .. 9 ms (flushed at 9 ms) */
    assert_int_equal(rows(h5_b, "/output/time"), 4);     /* t = 0, 3, 6, 9 ms */

    /* A'': killed right after the checkpoint before step 7: its rows are in fem.h5 (written
     * for the checkpoint; else only the first output step's would be, the rest in memory) */
    {
        char dir_c[600], h5_c[700];
        static reply_rec rc_[N_STEPS][N_IT];
        memset(rc_, 0, sizeof rc_);
        double u_c[3 * 64] = {0}, v_c[3 * 64] = {0};
        out_dir("k", dir_c, sizeof dir_c);
        open_session(&ss, json, dir_c, "k");
        run_steps(&ss, 0, K_RESUME, rc_, u_c, v_c);
        nc_error err;
        if (command(&ss, PROTO_MSG_CHECKPOINT, K_RESUME, K_RESUME * DT, "step_000007", &err))
            fail_msg("checkpoint: %s", err.message);
        kill_session(&ss);
        snprintf(h5_c, sizeof h5_c, "%s/fem.h5", dir_c);
        assert_int_equal(rows(h5_c, "/monitor/time"), K_RESUME + 1);   /* t = 0 .. 7 ms */
        assert_int_equal(rows(h5_c, "/output/time"), 3);           /* t = 0, 3, 6 ms */
        free_recs(rc_);
    }

    /* B: a fresh process in dir_b resumes step 7 and gets A's commands */
    open_session(&ss, json, dir_b, "b");
    nc_error err;
    if (command(&ss, PROTO_MSG_RESUME, K_RESUME, K_RESUME * DT, "step_000007", &err))
        fail_msg("resume: %s", err.message);
    memcpy(u_k, u_at, sizeof u_k);
    memcpy(v_k, v_at, sizeof v_k);
    run_steps(&ss, K_RESUME, N_STEPS, rb, u_k, v_k);
    assert_int_equal(close_session(&ss), 0);

    for (int k = K_RESUME; k < N_STEPS; k++)
        for (int it = 0; it < N_IT; it++) {
            assert_int_equal(rb[k][it].size, ra[k][it].size);
            if (memcmp(rb[k][it].bytes, ra[k][it].bytes, ra[k][it].size) != 0)
                fail_msg("step %d iteration %d: the resumed reply differs from the uninterrupted one", k, it + 1);
        }
    /* the rock moved the net: the comparison is of a real motion */
    const double *u_end = (const double *)ra[N_STEPS - 1][N_IT - 1].bytes;
    assert_below(u_end[3 * ss.iface_of[CENTRE] + 2], -0.01);

    static const char *const series[] = {"/output/time", "/output/step", "/output/load_factor",
        "/output/displacement", "/output/velocity", "/output/position", "/output/axial_force",
        "/output/strain", "/output/reaction", "/monitor/time", "/monitor/displacement",
        "/monitor/velocity", "/monitor/node_ids", "/mesh/coordinates", "/mesh/elements"};
    for (size_t i = 0; i < sizeof series / sizeof *series; i++) {
        h5_blob a, b;
        read_blob(h5_a, series[i], &a);
        read_blob(h5_b, series[i], &b);
        assert_int_equal(a.rank, b.rank);
        for (int d = 0; d < a.rank; d++)
            if (a.dims[d] != b.dims[d])
                fail_msg("%s: dimension %d is %llu uninterrupted, %llu resumed", series[i], d,
                         (unsigned long long)a.dims[d], (unsigned long long)b.dims[d]);
        if (memcmp(a.data, b.data, a.bytes) != 0) fail_msg("%s differs after the resume", series[i]);
        free(a.data);
        free(b.data);
    }
    assert_int_equal(rows(h5_a, "/monitor/time"), N_STEPS + 1);
    assert_int_equal(rows(h5_a, "/output/time"), 7);   /* 0, 3, ..., 15 ms and the end, 16 ms */
    static const char *const attrs[] = {"max_magnitude", "max_time", "max_node"};
    for (int i = 0; i < 3; i++) {
        double x = read_attr(h5_a, "/output/displacement", attrs[i]);
        double y = read_attr(h5_b, "/output/displacement", attrs[i]);
        assert_memory_equal(&x, &y, sizeof x);
    }
    char xa[700], xb[700];
    snprintf(xa, sizeof xa, "%s/fem.xdmf", dir_a);
    snprintf(xb, sizeof xb, "%s/fem.xdmf", dir_b);
    size_t na, nb;
    char *ta = slurp(xa, &na), *tb = slurp(xb, &nb);
    assert_int_equal(na, nb);
    assert_memory_equal(ta, tb, na);
    free(ta);
    free(tb);
    /* only the two newest checkpoints are kept */
    assert_false(exists(ck_a, "fem_step_000004.h5"));
    assert_true(exists(ck_a, "fem_step_000007.h5"));
    assert_true(exists(ck_a, "fem_step_000010.h5"));
    assert_false(exists(ck_b, "fem_step_000004.h5"));
    assert_true(exists(ck_b, "fem_step_000007.h5"));
    assert_true(exists(ck_b, "fem_step_000010.h5"));
    assert_false(exists(ck_b, "fem_step_000010.h5.tmp"));
    free_recs(ra);
    free_recs(rx);
    free_recs(rb);
}

/* Copies dir_from/checkpoint/fem_<name>.h5 into dir_to/checkpoint/. */
static void copy_checkpoint(const char *dir_from, const char *dir_to, const char *name)
{
    char from[900], to[900], ck[800];
    snprintf(from, sizeof from, "%s/checkpoint/fem_%s.h5", dir_from, name);
    snprintf(ck, sizeof ck, "%s/checkpoint", dir_to);
    snprintf(to, sizeof to, "%s/fem_%s.h5", ck, name);
    nc_error err;
    assert_int_equal(nc_file_make_dirs(ck, &err), 0);
    size_t n;
    char *data = slurp(from, &n);
    FILE *f = fopen(to, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(data, 1, n, f), n);
    fclose(f);
    free(data);
}

static void expect_error(session *ss, proto_msg_type type, long step, const char *text,
                         const char *want1, const char *want2)
{
    nc_error err;
    assert_int_equal(command(ss, type, step, step * DT, text, &err), -1);
    assert_int_equal(err.code, PROTO_ERR_PEER);
    print_message("expected error reply: %s\n", err.message);
    if (!strstr(err.message, want1) || (want2 && !strstr(err.message, want2)))
        fail_msg("the error does not name '%s'%s%s: %s", want1, want2 ? " and " : "",
                 want2 ? want2 : "", err.message);
}

static void test_resume_errors(void **state)
{
    (void)state;
    if (!getenv("NC_BIN")) skip();
    const char *json = net_json("ck_err.json", 7, 1e11);
    char dir_src[600], dir_c[600], dir_d[600], dir_e[600];
    out_dir("src", dir_src, sizeof dir_src);
    out_dir("c", dir_c, sizeof dir_c);
    out_dir("d", dir_d, sizeof dir_d);
    out_dir("e", dir_e, sizeof dir_e);
    static reply_rec rs[N_STEPS][N_IT], rc[N_STEPS][N_IT];
    memset(rs, 0, sizeof rs);
    memset(rc, 0, sizeof rc);
    double u_k[3 * 64] = {0}, v_k[3 * 64] = {0};

    /* a checkpoint of step 4 to resume from */
    session ss;
    open_session(&ss, json, dir_src, "src");
    run_steps(&ss, 0, 5, rs, u_k, v_k);
    assert_int_equal(close_session(&ss), 0);
    copy_checkpoint(dir_src, dir_c, "step_000004");
    copy_checkpoint(dir_src, dir_d, "step_000004");
    copy_checkpoint(dir_src, dir_e, "step_000004");

    /* the same model: a missing checkpoint, another step; then refusals inside the run */
    open_session(&ss, json, dir_c, "c");
    expect_error(&ss, PROTO_MSG_RESUME, 3, "step_000003", "checkpoint/fem_step_000003.h5", NULL);
    expect_error(&ss, PROTO_MSG_RESUME, 5, "step_000004", "fem_step_000004.h5", "holds step 4");
    expect_error(&ss, PROTO_MSG_RESUME, 5, "../x", "checkpoint name", NULL);
    char h5_c[700];
    snprintf(h5_c, sizeof h5_c, "%s/fem.h5", dir_c);
    struct stat st;
    assert_int_not_equal(stat(h5_c, &st), 0);   /* no results before the first step */
    /* a failed resume leaves the fresh state: step 0 as in the uninterrupted run */
    memset(u_k, 0, sizeof u_k);
    memset(v_k, 0, sizeof v_k);
    run_steps(&ss, 0, 1, rc, u_k, v_k);
    for (int it = 0; it < N_IT; it++) {
        assert_int_equal(rc[0][it].size, rs[0][it].size);
        assert_memory_equal(rc[0][it].bytes, rs[0][it].bytes, rs[0][it].size);
    }
    nc_error err;
    assert_int_equal(command(&ss, PROTO_MSG_BEGIN_STEP, 1, DT, NULL, &err), 0);
    expect_error(&ss, PROTO_MSG_CHECKPOINT, 1, "inside", "step is open", NULL);
    /* the solver keeps serving: the step goes on (and its reply is A's) */
    run_steps(&ss, 1, 2, rc, u_k, v_k);   /* begins step 1 again: restores first */
    for (int it = 0; it < N_IT; it++) assert_memory_equal(rc[1][it].bytes, rs[1][it].bytes, rs[1][it].size);
    expect_error(&ss, PROTO_MSG_RESUME, 2, "step_000004", "before the first begin_step", NULL);
    assert_int_equal(close_session(&ss), 1);   /* commands failed during the run */
    assert_int_equal(rows(h5_c, "/monitor/time"), 3);

    /* another model: 9 x 9 nodes */
    open_session(&ss, net_json("ck_err9.json", 9, 1e11), dir_d, "d");
    expect_error(&ss, PROTO_MSG_RESUME, 4, "step_000004", "fem_step_000004.h5", "49 nodes there, 81 in this one");
    assert_int_equal(close_session(&ss), 1);
    /* the same counts, other ropes (E 2e11 Pa) */
    open_session(&ss, net_json("ck_err_e.json", 7, 2e11), dir_e, "e");
    expect_error(&ss, PROTO_MSG_RESUME, 4, "step_000004", "fem_step_000004.h5", "element properties");
    assert_int_equal(close_session(&ss), 1);
    free_recs(rs);
    free_recs(rc);
}

int main(void)
{
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_in_process_resume),
        cmocka_unit_test(test_in_process_resume_brakes),
        cmocka_unit_test(test_resume_bit_identical),
        cmocka_unit_test(test_resume_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
