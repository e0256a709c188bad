/* chk_interface — the coupling interface netcouple-check works with: received from a FEM
 * participant, or sent to a DEM participant (read from a JSON file, or a small synthetic net).
 *
 * JSON form (what --save-interface writes and --interface reads):
 *   {"node_ids": [0, 1, ...], "coordinates": [[x, y, z], ...], "elements": [[a, b], ...]}
 * with element entries 0-based indices into the node list (protocol/README.md §3).
 */
#ifndef CHK_INTERFACE_H
#define CHK_INTERFACE_H

#include <stddef.h>
#include <stdint.h>
#include "proto.h"

typedef struct chk_interface {
    size_t n;           /* nodes */
    size_t m;           /* line elements */
    int32_t *node_ids;  /* [n] */
    double *coords;     /* [n, 3] reference coordinates [m] */
    int32_t *elements;  /* [m, 2] */
} chk_interface;

void chk_interface_free(chk_interface *f);
/* 3 x 3 nodes 0.5 m apart in the plane z = 0 centred at the origin, 12 grid-line elements. */
int chk_interface_synthetic(chk_interface *f, nc_error *err);
/* From a FEM's interface reply: checks shapes and indices (err says what is wrong). */
int chk_interface_from_reply(chk_interface *f, const proto_message *reply, nc_error *err);
int chk_interface_read(chk_interface *f, const char *path, nc_error *err);
int chk_interface_write(const chk_interface *f, const char *path, nc_error *err);
/* Adds node_ids, coordinates and elements to a command (pointing into f). */
int chk_interface_add(const chk_interface *f, proto_message *m, nc_error *err);
/* Index of the node nearest the centroid of the nodes (a free node of a supported net). */
size_t chk_interface_central_node(const chk_interface *f);

#endif
