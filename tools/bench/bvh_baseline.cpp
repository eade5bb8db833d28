// Verbatim copy of the pre-issue-12 builder (see bvh_baseline.h).
#include "bvh_baseline.h"
#include "util/timer.h"

#include <algorithm>
#include <cstring>

namespace baseline {
using et::Timer;
namespace {

struct Box {
    glm::vec3 lo{1e30f}, hi{-1e30f};
    void grow(const glm::vec3& p) {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
    void grow(const Box& b) {
        lo = glm::min(lo, b.lo);
        hi = glm::max(hi, b.hi);
    }
    float area() const {
        glm::vec3 d = hi - lo;
        return d.x < 0.0f ? 0.0f : 2.0f * (d.x * d.y + d.y * d.z + d.z * d.x);
    }
};

constexpr int kBins = 16;
constexpr int kMaxDepth = BASELINE_BVH_STACK - 4;

float as_float_bits(uint32_t u) {
    float f;
    std::memcpy(&f, &u, 4);
    return f;
}

// The binary tree as built, before flattening into the kernels' two-box layout.
struct TreeNode {
    Box box;
    int left = -1, right = -1; // children; -1 for a leaf
    int first = 0, count = 0;  // leaf triangles
};

struct Builder {
    const std::vector<Box>& boxes;
    const std::vector<glm::vec3>& centroids;
    std::vector<int>& order;
    std::vector<TreeNode>& nodes;
    int max_leaf;
    int depth = 0;
    double cost = 0.0;
    float root_area = 1.0f;

    void set_leaf(int n, const Box& b, int first, int count) {
        nodes[n].box = b;
        nodes[n].first = first;
        nodes[n].count = count;
    }

    void build(int node, int begin, int end, int level) {
        depth = std::max(depth, level);
        Box bounds, cbounds;
        for (int i = begin; i < end; ++i) {
            bounds.grow(boxes[order[i]]);
            cbounds.grow(centroids[order[i]]);
        }
        const int count = end - begin;
        const float area = bounds.area();
        auto make_leaf = [&] {
            set_leaf(node, bounds, begin, count);
            cost += area / root_area * count;
        };
        if (count <= 1 || level >= kMaxDepth) {
            make_leaf();
            return;
        }
        // Binned SAH over the largest centroid extent.
        glm::vec3 ext = cbounds.hi - cbounds.lo;
        int axis = ext.x > ext.y ? (ext.x > ext.z ? 0 : 2) : (ext.y > ext.z ? 1 : 2);
        int split = -1;
        float best = 1e30f;
        if (ext[axis] > 0.0f) {
            Box bin_box[kBins];
            int bin_count[kBins] = {};
            const float scale = kBins / ext[axis];
            auto bin_of = [&](int t) {
                return std::min(kBins - 1,
                                static_cast<int>((centroids[t][axis] - cbounds.lo[axis]) * scale));
            };
            for (int i = begin; i < end; ++i) {
                int b = bin_of(order[i]);
                ++bin_count[b];
                bin_box[b].grow(boxes[order[i]]);
            }
            float right_area[kBins];
            int right_count[kBins];
            Box acc;
            int n = 0;
            for (int b = kBins - 1; b > 0; --b) {
                acc.grow(bin_box[b]);
                n += bin_count[b];
                right_area[b] = acc.area();
                right_count[b] = n;
            }
            acc = Box();
            n = 0;
            for (int b = 0; b < kBins - 1; ++b) {
                acc.grow(bin_box[b]);
                n += bin_count[b];
                if (n == 0 || right_count[b + 1] == 0)
                    continue;
                float c = acc.area() * n + right_area[b + 1] * right_count[b + 1];
                if (c < best) {
                    best = c;
                    split = b;
                }
            }
            // SAH: traversal cost 1, intersection cost 1 per triangle.
            if (split >= 0 && count <= max_leaf && best / area + 1.0f >= count)
                split = -1;
            if (split >= 0) {
                auto mid = std::partition(order.begin() + begin, order.begin() + end,
                                          [&](int t) { return bin_of(t) <= split; });
                int m = static_cast<int>(mid - order.begin());
                emit_inner(node, bounds, begin, m, end, level, area);
                return;
            }
        }
        if (count <= max_leaf) {
            make_leaf();
            return;
        }
        // All centroids coincide (or no SAH split): split the range in half.
        std::nth_element(order.begin() + begin, order.begin() + (begin + end) / 2,
                         order.begin() + end,
                         [&](int a, int b) { return centroids[a][axis] < centroids[b][axis]; });
        emit_inner(node, bounds, begin, (begin + end) / 2, end, level, area);
    }

    void emit_inner(int node, const Box& bounds, int begin, int mid, int end, int level,
                    float area) {
        cost += area / root_area;
        const int left = static_cast<int>(nodes.size());
        nodes.emplace_back();
        build(left, begin, mid, level + 1);
        const int right = static_cast<int>(nodes.size());
        nodes.emplace_back();
        build(right, mid, end, level + 1);
        nodes[node].box = bounds;
        nodes[node].left = left;
        nodes[node].right = right;
    }
};

// Flattens the tree depth-first into inner nodes of four float4 (kernels/bvh.h): each holds both
// children's boxes; a leaf child carries its triangles, an inner child its node index.
struct Flattener {
    const std::vector<TreeNode>& tree;
    std::vector<etk::float4>& out;

    void child(int slot, int c) {
        const TreeNode& t = tree[c];
        uint32_t meta, flags;
        if (t.left < 0) {
            meta = static_cast<uint32_t>(t.first);
            flags = 0x80000000u | static_cast<uint32_t>(t.count);
        } else {
            meta = static_cast<uint32_t>(emit(c));
            flags = 0u;
        }
        out[slot] = etk::make_float4(t.box.lo.x, t.box.lo.y, t.box.lo.z, as_float_bits(meta));
        out[slot + 1] = etk::make_float4(t.box.hi.x, t.box.hi.y, t.box.hi.z, as_float_bits(flags));
    }
    int emit(int n) {
        const int index = static_cast<int>(out.size() / 4);
        out.resize(out.size() + 4);
        child(4 * index, tree[n].left);
        child(4 * index + 2, tree[n].right);
        return index;
    }
};

} // namespace

Bvh build_bvh(const et::TriangleSoup& soup, int max_leaf) {
    Timer timer;
    Bvh bvh;
    const int n = static_cast<int>(soup.size());
    std::vector<Box> boxes(n);
    std::vector<glm::vec3> centroids(n);
    for (int t = 0; t < n; ++t) {
        for (int k = 0; k < 3; ++k)
            boxes[t].grow(soup.positions[3 * t + k]);
        centroids[t] = 0.5f * (boxes[t].lo + boxes[t].hi);
    }
    bvh.order.resize(n);
    for (int t = 0; t < n; ++t)
        bvh.order[t] = t;
    std::vector<TreeNode> tree(1);
    if (n > 0) {
        Builder b{boxes, centroids, bvh.order, tree, std::max(1, max_leaf)};
        Box root;
        for (const auto& bx : boxes)
            root.grow(bx);
        b.root_area = std::max(root.area(), 1e-30f);
        b.build(0, 0, n, 0);
        bvh.depth = b.depth;
        bvh.sah_cost = b.cost;
    }
    if (tree[0].left < 0) {
        // A single leaf (or no triangle at all): a root whose children are that leaf and an
        // empty one, so the kernels always start from an inner node.
        TreeNode leaf = tree[0], empty;
        empty.box.lo = empty.box.hi = glm::vec3(0.0f);
        if (n == 0)
            leaf = empty;
        tree.assign(1, TreeNode{});
        tree[0].left = 1;
        tree[0].right = 2;
        tree.push_back(leaf);
        tree.push_back(empty);
    }
    Flattener f{tree, bvh.nodes};
    f.emit(0);
    bvh.build_seconds = timer.seconds();
    return bvh;
}

} // namespace baseline
