// Bounding volume hierarchy over a triangle soup: binned SAH build, flattened to the layout the
// kernels traverse (kernels/bvh.h).
#pragma once
#include "kernels/bvh.h"
#include "load/scene.h"

#include <utility>
#include <vector>

namespace et {

struct Bvh {
    std::vector<etk::float4> nodes; // ETK_BVH_NODE per 8-wide node (kernels/bvh.h)
    std::vector<int> order; // triangle order: flattened triangle i is soup triangle order[i]
    // (first flattened triangle, count) of each non-empty leaf, in the order of their packets
    std::vector<std::pair<int, int>> leaves;
    int depth = 0;      // of the binary tree the builder made (leaves' level)
    int wide_depth = 0; // of the 8-wide tree the kernels traverse (nodes on the longest path)
    int stack = 0;      // entries a traversal's stack may hold at most (<= ETK_BVH_STACK)
    double build_seconds = 0.0;
    double sah_cost = 0.0; // of the binary tree: traversal 1, triangle test 1, per root area
    int node_count() const { return static_cast<int>(nodes.size() / ETK_BVH_NODE); }
};

// Leaves hold at most `max_leaf` triangles; depth stays below the kernels' stack size.
// threads: 0 for all cores; the tree is the same, bit for bit, for any count.
Bvh build_bvh(const TriangleSoup& soup, int max_leaf = 4, int threads = 0);

// A binary tree as a builder makes it, before flattening into the kernels' layout. Node 0 is the
// root; a leaf (left < 0) holds triangles order[first .. first + count).
struct BvhTreeNode {
    glm::vec3 lo{1e30f}, hi{-1e30f};
    int left = -1, right = -1;
    int first = 0, count = 0;
};

// The kernels' layout of any binary tree (also one made by another builder: tools/bench), with
// its depth and SAH cost; build_seconds is left to the caller.
Bvh flatten_bvh(std::vector<BvhTreeNode> tree, std::vector<int> order);

// Triangles in BVH order: v0, e1, e2 (three float4 each; tests and benchmarks); one all-zero
// triangle for an empty soup.
std::vector<etk::float4> flatten_triangles(const TriangleSoup& soup, const std::vector<int>& order);

// Geometric normals in BVH order, normalize(cross(e1, e2)) of the edges above (so the very bits
// the kernels computed from them before); one zero normal for an empty soup.
std::vector<etk::float4> face_normals(const TriangleSoup& soup, const std::vector<int>& order);

// The leaves' triangles as the traversal reads them: packets of four (kernels/bvh.h), each leaf's
// from the index its node gives; one packet of unused lanes when there is no triangle. `slots`,
// if given, receives where each triangle (BVH order) sits: packet index x 4 + lane, so that a
// hit's vertices can be read back (kernels/surface.h, etk_hit_point); one entry when there is no
// triangle.
std::vector<etk::float4> flatten_packets(const TriangleSoup& soup, const Bvh& bvh,
                                         std::vector<int>* slots = nullptr);

// Appends one packet (ETK_BVH_PACKET float4) holding flattened triangles lanes[0..3], where
// flattened triangle i is soup triangle order[i]; -1 is an unused lane.
void append_packet(const TriangleSoup& soup, const std::vector<int>& order, const int lanes[4],
                   std::vector<etk::float4>& out);

} // namespace et
