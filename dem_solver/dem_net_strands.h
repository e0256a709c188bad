/* dem_net_strands — which edges at a net node belong to one rope (a strand), so that a sphere
 * touching the node touches each rope through it once (dem_detect_net.c).
 *
 * Contract: dem_net_find_strands() fills strand[2 e + s] for the end s (0: edges[2 e], 1:
 * edges[2 e + 1]) of every edge e with the strand that end belongs to at its node: the smaller
 * index of the two edges paired there; e itself at a free end (the only edge of any length
 * at its node); and DEM_NET_ATTACHED_END(e) where e ends unpaired at a node that other edges
 * pass through (the end of a rope fastened to another: a sphere touching it there touches the
 * rope it is fastened to, so dem_detect_net.c makes it no node contact of its own). At each
 * node the edges are paired most nearly opposite first (the outgoing directions at the given
 * coordinates with the smallest cosine); a node of two edges is one strand at any angle (a
 * rope bending there), a crossing of two ropes is two, a node of three edges a rope and the
 * attached end of another. An edge of zero length pairs with none and is an attached end at
 * both of its nodes. The pairing is geometric: the interface names edges, not ropes, so a
 * mesh whose wires zig-zag through its nodes may be paired otherwise than it was woven. */
#ifndef DEM_NET_STRANDS_H
#define DEM_NET_STRANDS_H

#include <stddef.h>
#include <stdint.h>

#include "nc_error.h"

/* The strand value of edge e's end fastened to another rope (negative, so never an edge). */
#define DEM_NET_ATTACHED_END(e) (-1 - (int32_t)(e))

int dem_net_find_strands(size_t n_nodes, const double *coords, size_t n_edges,
                         const int32_t *edges, int32_t *strand, nc_error *err);

#endif
