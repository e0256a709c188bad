/* test_gmsh_input — the Gmsh reader under hostile counts: every count, tag count and index
 * read from a .msh file is bounded, and a file that breaks a bound is refused with a message
 * naming the file, the line and the field (under the sanitizer build an out-of-bounds access
 * would abort the test instead). */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <stdio.h>
#include <string.h>

#include "../../fem_solver/fem_mesh_gmsh.h"
#include "fem_test_util.h"

/* Reads `text` as a .msh file; expects a refusal whose message holds every given piece. */
static void expect_refused(const char *name, const char *text, const char *const *pieces)
{
    const char *path = fem_test_write(name, text);
    fem_gmsh_mesh g;
    nc_error err;
    if (fem_gmsh_read(path, &g, &err) == 0) {
        fem_gmsh_free(&g);
        fail_msg("%s: accepted", name);
    }
    if (!strstr(err.message, name)) fail_msg("%s: message does not name the file: %s", name, err.message);
    for (const char *const *p = pieces; *p; p++)
        if (!strstr(err.message, *p)) fail_msg("%s: message lacks \"%s\": %s", name, *p, err.message);
}

#define HEAD2 "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"
#define HEAD4 "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
#define NODES2 "$Nodes\n3\n1 0 0 0\n2 1 0 0\n3 2 0 0\n$EndNodes\n"

/* A 4.1 node block announcing -1 nodes: it used to shift the write position before the
 * node arrays (heap-buffer-overflow write). */
static void test_negative_node_block(void **state)
{
    (void)state;
    static const char *const pieces[] = {"line 6", "node block 1", "numNodesInBlock -1", NULL};
    expect_refused("block_minus1.msh",
                   HEAD4 "$Nodes\n1 2 1 2\n0 1 0 -1\n1\n2\n0 0 0\n1 0 0\n$EndNodes\n", pieces);
    static const char *const too_many[] = {"line 6", "numNodesInBlock 3", NULL};
    expect_refused("block_over.msh",
                   HEAD4 "$Nodes\n1 2 1 2\n0 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n2 0 0\n$EndNodes\n", too_many);
    static const char *const blocks[] = {"line 5", "numEntityBlocks -3", NULL};
    expect_refused("blocks_neg.msh", HEAD4 "$Nodes\n-3 2 1 2\n$EndNodes\n", blocks);
}

/* A 2.2 element line with number-of-tags -5: it used to read before the array holding the
 * line's numbers (stack-buffer-overflow read). */
static void test_negative_tag_count(void **state)
{
    (void)state;
    static const char *const pieces[] = {"line 12", "element 1", "number-of-tags -5", NULL};
    expect_refused("tags_minus5.msh", HEAD2 NODES2 "$Elements\n1\n5 1 -5 3 4\n$EndElements\n", pieces);
    static const char *const over[] = {"line 12", "number-of-tags 9", NULL};
    expect_refused("tags_over.msh", HEAD2 NODES2 "$Elements\n1\n5 1 9 1 2\n$EndElements\n", over);
}

/* The other counts and indices of a file. */
static void test_other_counts(void **state)
{
    (void)state;
    static const char *const nodes0[] = {"line 5", "number of nodes -4", NULL};
    expect_refused("nodes_neg.msh", HEAD2 "$Nodes\n-4\n$EndNodes\n", nodes0);
    static const char *const fewer[] = {"$Nodes", "node 3", NULL};
    expect_refused("nodes_short.msh", HEAD2 "$Nodes\n3\n1 0 0 0\n2 1 0 0\n$EndNodes\n", fewer);
    static const char *const nan[] = {"line 6", "node 1", "coordinate y", NULL};
    expect_refused("nodes_nan.msh", HEAD2 "$Nodes\n1\n1 0 nan 0\n$EndNodes\n", nan);
    static const char *const elems[] = {"line 11", "number of elements -2", NULL};
    expect_refused("elems_neg.msh", HEAD2 NODES2 "$Elements\n-2\n$EndElements\n", elems);
    static const char *const unknown[] = {"line 12", "element 1", "unknown node tag 7", NULL};
    expect_refused("elems_tag.msh", HEAD2 NODES2 "$Elements\n1\n1 1 0 1 7\n$EndElements\n", unknown);
    static const char *const three[] = {"line 12", "element 1", "gives 3", NULL};
    expect_refused("elems_three.msh", HEAD2 NODES2 "$Elements\n1\n1 1 0 1 2 3\n$EndElements\n", three);
    static const char *const block[] = {"line 14", "element block 1", "numElementsInBlock -7", NULL};
    expect_refused("eblock_neg.msh",
                   HEAD4 "$Nodes\n1 2 1 2\n0 1 0 2\n1\n2\n0 0 0\n1 0 0\n$EndNodes\n"
                         "$Elements\n1 1 1 1\n1 1 1 -7\n1 1 2\n$EndElements\n", block);
    static const char *const ents[] = {"line 5", "$Entities", "-1", NULL};
    expect_refused("ents_neg.msh", HEAD4 "$Entities\n-1 0 0 0\n$EndEntities\n", ents);
    static const char *const names[] = {"line 5", "$PhysicalNames", NULL};
    expect_refused("names_neg.msh", HEAD2 "$PhysicalNames\n-1\n$EndPhysicalNames\n", names);
    static const char *const twice[] = {"line 10", "a second $Nodes", NULL};
    expect_refused("nodes_twice.msh", HEAD2 NODES2 NODES2, twice);
}

/* A valid 2.2 file still reads, with a huge announced count refused before any allocation
 * of that size. */
static void test_valid_and_huge(void **state)
{
    (void)state;
    const char *path = fem_test_write("ok.msh", HEAD2 NODES2 "$Elements\n2\n1 1 2 7 1 1 2\n2 1 0 2 3\n$EndElements\n");
    fem_gmsh_mesh g;
    nc_error err;
    if (fem_gmsh_read(path, &g, &err)) fail_msg("%s", err.message);
    assert_int_equal(g.n_nodes, 3);
    assert_int_equal(g.n_lines, 2);
    assert_int_equal(g.line_physical[0], 7);
    assert_int_equal(g.lines[3], 2);
    fem_gmsh_free(&g);
    static const char *const huge[] = {"line 5", "number of nodes 9000000000", NULL};
    expect_refused("nodes_huge.msh", HEAD2 "$Nodes\n9000000000\n$EndNodes\n", huge);
    /* announced within bounds but not present: storage follows what is read */
    static const char *const absent[] = {"$Nodes", "node 2", NULL};
    expect_refused("nodes_absent.msh", HEAD2 "$Nodes\n40000000\n1 0 0 0\n$EndNodes\n", absent);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_negative_node_block),
        cmocka_unit_test(test_negative_tag_count),
        cmocka_unit_test(test_other_counts),
        cmocka_unit_test(test_valid_and_huge),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
