#include "prepare/bvh_build.h"

#include "kernels/bvh.h"
#include "util/error.h"
#include "util/parallel.h"
#include "util/timer.h"

#include <algorithm>
#include <cstring>
#include <string>

namespace et {
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

constexpr int kBins = 32;
// Triangles the kernels test at once (a packet, kernels/bvh.h): the SAH's unit of intersection.
int packets(int triangles) {
    return (triangles + 3) / 4;
}
// Binary depth limit: wide nodes of four children, each two binary levels down, would make at
// most 31 levels and a path's stack of at most 1 + 3 x 30 entries, the bound the flattener keeps
// to (Flattener, kernels/bvh.h).
constexpr int kMaxDepth = 60;
// A split's two subtrees are built on two threads when both have at least this many triangles
// (and neither more than three times the other).
constexpr int kParallelTriangles = 1 << 14;

float as_float_bits(uint32_t u) {
    float f;
    std::memcpy(&f, &u, 4);
    return f;
}

struct Builder {
    const std::vector<Box>& boxes;
    const std::vector<glm::vec3>& centroids;
    std::vector<int>& order;
    std::vector<BvhTreeNode>& nodes;
    int max_leaf;
    int threads; // for subtrees: split between the two sides of a split (emit_inner)

    // Appends a subtree built on its own (root at index 0); returns its root's index here.
    int append(const std::vector<BvhTreeNode>& sub) {
        const int base = static_cast<int>(nodes.size());
        for (BvhTreeNode t : sub) {
            if (t.left >= 0) {
                t.left += base;
                t.right += base;
            }
            nodes.push_back(t);
        }
        return base;
    }
    void set_leaf(int n, const Box& b, int first, int count) {
        nodes[n].lo = b.lo;
        nodes[n].hi = b.hi;
        nodes[n].first = first;
        nodes[n].count = count;
    }

    int bin_of(int t, int axis, float lo, float scale) const {
        return std::min(kBins - 1, static_cast<int>((centroids[t][axis] - lo) * scale));
    }

    void build(int node, int begin, int end, int level) {
        Box bounds, cbounds;
        for (int i = begin; i < end; ++i) {
            bounds.grow(boxes[order[i]]);
            cbounds.grow(centroids[order[i]]);
        }
        const int count = end - begin;
        const float area = bounds.area();
        auto make_leaf = [&] { set_leaf(node, bounds, begin, count); };
        if (count <= 1 || level >= kMaxDepth) {
            make_leaf();
            return;
        }
        // Binned SAH over all three axes (the largest extent alone left the SAH cost
        // of the bunny scene 1.7x that of Embree's builder); the cheapest split wins.
        glm::vec3 ext = cbounds.hi - cbounds.lo;
        int axis = ext.x > ext.y ? (ext.x > ext.z ? 0 : 2) : (ext.y > ext.z ? 1 : 2);
        int split = -1, split_axis = -1;
        float best = 1e30f;
        // One pass bins the triangles along all three axes.
        Box bin_box[3][kBins];
        int bin_count[3][kBins] = {};
        float scale[3];
        for (int ax = 0; ax < 3; ++ax)
            scale[ax] = ext[ax] > 0.0f ? kBins / ext[ax] : 0.0f;
        for (int i = begin; i < end; ++i) {
            const int t = order[i];
            for (int ax = 0; ax < 3; ++ax) {
                const int b = bin_of(t, ax, cbounds.lo[ax], scale[ax]);
                ++bin_count[ax][b];
                bin_box[ax][b].grow(boxes[t]);
            }
        }
        for (int ax = 0; ax < 3; ++ax) {
            if (!(ext[ax] > 0.0f))
                continue;
            float right_area[kBins];
            int right_count[kBins];
            Box acc;
            int n = 0;
            for (int b = kBins - 1; b > 0; --b) {
                acc.grow(bin_box[ax][b]);
                n += bin_count[ax][b];
                right_area[b] = acc.area();
                right_count[b] = n;
            }
            acc = Box();
            n = 0;
            for (int b = 0; b < kBins - 1; ++b) {
                acc.grow(bin_box[ax][b]);
                n += bin_count[ax][b];
                if (n == 0 || right_count[b + 1] == 0)
                    continue;
                float c = acc.area() * packets(n) + right_area[b + 1] * packets(right_count[b + 1]);
                if (c < best) {
                    best = c;
                    split = b;
                    split_axis = ax;
                }
            }
        }
        // SAH: traversal cost 1, intersection cost 1 per packet of four triangles (the kernels
        // test a packet's four at once: kernels/bvh.h).
        if (split >= 0 && count <= max_leaf && best / area + 1.0f >= packets(count))
            split = -1;
        if (split >= 0) {
            const float lo = cbounds.lo[split_axis], scale = kBins / ext[split_axis];
            auto mid = std::partition(order.begin() + begin, order.begin() + end, [&](int t) {
                return bin_of(t, split_axis, lo, scale) <= split;
            });
            int m = static_cast<int>(mid - order.begin());
            emit_inner(node, bounds, begin, m, end, level);
            return;
        }
        if (count <= max_leaf) {
            make_leaf();
            return;
        }
        // All centroids coincide (or no SAH split): split the range in half.
        std::nth_element(order.begin() + begin, order.begin() + (begin + end) / 2,
                         order.begin() + end,
                         [&](int a, int b) { return centroids[a][axis] < centroids[b][axis]; });
        emit_inner(node, bounds, begin, (begin + end) / 2, end, level);
    }

    void emit_inner(int node, const Box& bounds, int begin, int mid, int end, int level) {
        int left, right;
        const int small = std::min(mid - begin, end - mid);
        if (threads > 1 && small >= kParallelTriangles && 4 * small >= end - begin) {
            // The first split whose sides are both large and within 1:3 of each other (the root's
            // often peels a ground plane or a small object off the rest, and a thread given the
            // small side would idle): its subtrees on two threads, each into a tree of its own,
            // then appended the way the serial recursion lays them out (left subtree, then
            // right): the same tree, bit for bit, for any thread count. They partition disjoint
            // ranges of order.
            std::vector<BvhTreeNode> sub[2] = {std::vector<BvhTreeNode>(1),
                                               std::vector<BvhTreeNode>(1)};
            run_on_threads(2, [&](int t) {
                Builder b{boxes, centroids, order, sub[t], max_leaf, threads / 2};
                b.build(0, t == 0 ? begin : mid, t == 0 ? mid : end, level + 1);
            });
            left = append(sub[0]);
            right = append(sub[1]);
        } else {
            left = static_cast<int>(nodes.size());
            nodes.emplace_back();
            build(left, begin, mid, level + 1);
            right = static_cast<int>(nodes.size());
            nodes.emplace_back();
            build(right, mid, end, level + 1);
        }
        nodes[node].lo = bounds.lo;
        nodes[node].hi = bounds.hi;
        nodes[node].left = left;
        nodes[node].right = right;
    }
};

// Flattens the binary tree depth-first into 8-wide nodes (kernels/bvh.h). A node's children are
// those of least SAH cost (plan: each binary subtree spread over at most eight lanes). Leaf
// children carry their packets (recorded in `leaves`), inner ones their node index. Measures the
// binary tree's depth and SAH cost on the way.
//
// The traversal's stack: a node with k inner children entered pushes k and pops one, so a path
// holds at most the sum of its nodes' k - 1, plus one. A node takes the plan's children only where
// what its subtrees could still push keeps within ETK_BVH_STACK; otherwise its binary node's
// children, each inner one replaced by its own two (so the path descends at least two binary
// levels), and more, greedy by area, only as far as that holds: the first four alone (the binary
// levels halve, three pushes per level) always keep within it, from kMaxDepth.
struct Flattener {
    const std::vector<BvhTreeNode>& tree;
    std::vector<etk::float4>& out;
    std::vector<std::pair<int, int>>& leaves;
    int packet_count = 0;
    double root_area = 1.0;
    double cost = 0.0;
    int depth = 0, wide_depth = 0, stack = 0;
    std::vector<int> height{}; // of each binary node's subtree (a leaf: 0)

    // Surface area in doubles: finite for any box (flatten_bvh also takes other builders'
    // trees), so the plan's costs never become 0 or NaN.
    static double box_area(const glm::vec3& lo, const glm::vec3& hi) {
        const double x = double(hi.x) - lo.x, y = double(hi.y) - lo.y, z = double(hi.z) - lo.z;
        return x < 0.0 ? 0.0 : 2.0 * (x * y + y * z + z * x);
    }
    double area(const BvhTreeNode& t) const { return box_area(t.lo, t.hi) / root_area; }
    // SAH cost, depth and heights of the binary tree below n (at `level`).
    int measure(int n, int level) {
        const BvhTreeNode& t = tree[n];
        int h = 0;
        if (t.left < 0) {
            cost += area(t) * t.count;
            depth = std::max(depth, level);
        } else {
            cost += area(t);
            const int hl = measure(t.left, level + 1); // left first: the cost's sum in order
            h = 1 + std::max(hl, measure(t.right, level + 1));
        }
        height[static_cast<size_t>(n)] = h;
        return h;
    }
    // Whether children `kids` keep a path that arrives with `used` stack entries within the
    // stack: their pushes here, then at most three per two binary levels below.
    bool fits(const std::vector<int>& kids, int used) const {
        int inner = 0, h = 0;
        for (int c : kids)
            if (tree[c].left >= 0) {
                ++inner;
                h = std::max(h, height[static_cast<size_t>(c)]);
            }
        return inner == 0 || used + inner - 1 + 3 * ((h + 1) / 2) + 1 <= ETK_BVH_STACK;
    }
    // SAH-optimal collapse (dynamic programming over the binary tree, as Ylitie, Karras and Laine
    // 2017 do for their 8-wide trees): best[W * n + i - 1] is the least SAH cost of binary node
    // n's subtree spread over at most i children of a wide node (a leaf: its packets; an inner
    // node as one child: a wide node of its own, traversal cost 1), split[...] how: 0 as one
    // child, k > 0 its left subtree over k children and its right over i - k.
    static constexpr int W = ETK_BVH_WIDTH;
    std::vector<float> best{};
    std::vector<unsigned char> split{};
    std::vector<unsigned char> wide_split{}; // an inner node's own: its left's share of W lanes
    // The cost of n's children spread over at most i lanes, and the left's share.
    float spread(int n, int i, int* share) const {
        const BvhTreeNode& t = tree[n];
        const size_t l = static_cast<size_t>(W) * t.left, r = static_cast<size_t>(W) * t.right;
        float c = 3e38f;
        *share = 1; // a valid split whatever the costs
        for (int k = 1; k < i; ++k) {
            const float v = best[l + k - 1] + best[r + (i - k) - 1];
            if (v < c) {
                c = v;
                *share = k;
            }
        }
        return c;
    }
    void plan(int n) {
        const BvhTreeNode& t = tree[n];
        float* b = &best[static_cast<size_t>(W) * n];
        unsigned char* sp = &split[static_cast<size_t>(W) * n];
        if (t.left < 0) {
            for (int i = 0; i < W; ++i)
                b[i] = static_cast<float>(area(t) * packets(t.count)), sp[i] = 0;
            return;
        }
        plan(t.left);
        plan(t.right);
        int k = 0;
        b[0] = static_cast<float>(area(t)) + spread(n, W, &k);
        sp[0] = 0;
        wide_split[static_cast<size_t>(n)] = static_cast<unsigned char>(k);
        for (int i = 2; i <= W; ++i) {
            b[i - 1] = b[0];
            sp[i - 1] = 0;
            const float c = spread(n, i, &k);
            if (c < b[i - 1]) {
                b[i - 1] = c;
                sp[i - 1] = static_cast<unsigned char>(k);
            }
        }
    }
    // The children the plan gives binary node n over at most i lanes.
    void collect(int n, int i, std::vector<int>& kids) const {
        const int k = split[static_cast<size_t>(W) * n + i - 1];
        if (k == 0) {
            kids.push_back(n);
            return;
        }
        collect(tree[n].left, k, kids);
        collect(tree[n].right, i - k, kids);
    }
    // The children of the wide node made of inner binary node n: the plan's, or, where they would
    // not keep the stack within, the first four and greedy by area as far as they do.
    std::vector<int> children(int n, int used) const {
        std::vector<int> kids;
        const int k = wide_split[static_cast<size_t>(n)];
        collect(tree[n].left, k, kids);
        collect(tree[n].right, W - k, kids);
        if (fits(kids, used))
            return kids;
        kids.clear();
        for (int c : {tree[n].left, tree[n].right}) {
            if (tree[c].left < 0) {
                kids.push_back(c);
            } else {
                kids.push_back(tree[c].left);
                kids.push_back(tree[c].right);
            }
        }
        while (kids.size() < ETK_BVH_WIDTH) {
            int widest = -1;
            for (int j = 0; j < static_cast<int>(kids.size()); ++j)
                if (tree[kids[j]].left >= 0 &&
                    (widest < 0 || area(tree[kids[j]]) > area(tree[kids[widest]])))
                    widest = j;
            if (widest < 0)
                break;
            std::vector<int> wider = kids;
            const int c = wider[widest];
            wider[widest] = tree[c].left;
            wider.push_back(tree[c].right);
            if (kids.size() >= 4 && !fits(wider, used))
                break;
            kids = std::move(wider);
        }
        return kids;
    }
    int emit(int n, int level, int used) {
        wide_depth = std::max(wide_depth, level);
        const std::vector<int> kids = children(n, used);
        int inner = 0;
        for (int c : kids)
            inner += tree[c].left >= 0 ? 1 : 0;
        stack = std::max(stack, used + inner);
        const int index = static_cast<int>(out.size() / ETK_BVH_NODE);
        out.resize(out.size() + ETK_BVH_NODE);
        float lane[8][ETK_BVH_WIDTH];
        for (int k = 0; k < ETK_BVH_WIDTH; ++k) {
            uint32_t meta = 0u, flags = 0x80000000u; // an unused lane: empty leaf, point box
            glm::vec3 lo(0.0f), hi(0.0f);
            if (k < static_cast<int>(kids.size())) {
                const BvhTreeNode& t = tree[kids[k]];
                lo = t.lo;
                hi = t.hi;
                if (t.left < 0) {
                    meta = static_cast<uint32_t>(packet_count);
                    flags = 0x80000000u | static_cast<uint32_t>(packets(t.count));
                    packet_count += packets(t.count);
                    if (t.count > 0)
                        leaves.emplace_back(t.first, t.count);
                } else {
                    meta = static_cast<uint32_t>(emit(kids[k], level + 1, used + inner - 1));
                    flags = 0u;
                }
            }
            const float v[8] = {
                lo.x, lo.y, lo.z, hi.x, hi.y, hi.z, as_float_bits(meta), as_float_bits(flags)};
            for (int r = 0; r < 8; ++r)
                lane[r][k] = v[r];
        }
        for (int r = 0; r < 8; ++r)
            for (int q = 0; q < ETK_BVH_WIDTH / 4; ++q)
                out[ETK_BVH_NODE * index + (ETK_BVH_WIDTH / 4) * r + q] = etk::make_float4(
                    lane[r][4 * q], lane[r][4 * q + 1], lane[r][4 * q + 2], lane[r][4 * q + 3]);
        return index;
    }
};

} // namespace

Bvh build_bvh(const TriangleSoup& soup, int max_leaf, int threads) {
    Timer timer;
    const int n = static_cast<int>(soup.size());
    std::vector<Box> boxes(n);
    std::vector<glm::vec3> centroids(n);
    for (int t = 0; t < n; ++t) {
        for (int k = 0; k < 3; ++k)
            boxes[t].grow(soup.positions[3 * t + k]);
        centroids[t] = 0.5f * (boxes[t].lo + boxes[t].hi);
    }
    std::vector<int> order(n);
    for (int t = 0; t < n; ++t)
        order[t] = t;
    std::vector<BvhTreeNode> tree(1);
    if (n > 0) {
        Builder b{boxes, centroids, order, tree, std::max(1, max_leaf), thread_count(threads)};
        b.build(0, 0, n, 0);
    }
    Bvh bvh = flatten_bvh(std::move(tree), std::move(order));
    bvh.build_seconds = timer.seconds();
    return bvh;
}

Bvh flatten_bvh(std::vector<BvhTreeNode> tree, std::vector<int> order) {
    Bvh bvh;
    if (tree.empty() || order.empty()) {
        tree.assign(1, BvhTreeNode{});
        tree[0].lo = tree[0].hi = glm::vec3(0.0f);
    }
    if (tree[0].left < 0) {
        // A single leaf (or no triangle at all): a root whose children are that leaf and an
        // empty one, so the kernels always start from an inner node.
        BvhTreeNode leaf = tree[0], empty;
        empty.lo = empty.hi = glm::vec3(0.0f);
        if (order.empty())
            leaf = empty;
        tree.assign(1, BvhTreeNode{});
        tree[0].lo = leaf.lo;
        tree[0].hi = leaf.hi;
        tree[0].left = 1;
        tree[0].right = 2;
        tree.push_back(leaf);
        tree.push_back(empty);
    }
    Flattener f{tree, bvh.nodes, bvh.leaves};
    f.root_area = std::max(Flattener::box_area(tree[0].lo, tree[0].hi), 1e-30);
    f.height.assign(tree.size(), 0);
    f.best.assign(tree.size() * ETK_BVH_WIDTH, 0.0f);
    f.split.assign(tree.size() * ETK_BVH_WIDTH, 0);
    f.wide_split.assign(tree.size(), 1);
    f.measure(0, 0);
    f.plan(0);
    f.emit(0, 0, 0);
    if (f.stack > ETK_BVH_STACK) // never: kMaxDepth and Flattener::fits keep the trees within
        throw Error("BVH of depth " + std::to_string(f.wide_depth + 1) + " needs " +
                    std::to_string(f.stack) + " stack entries, more than the kernels' " +
                    std::to_string(ETK_BVH_STACK));
    bvh.depth = f.depth;
    bvh.wide_depth = f.wide_depth + 1;
    bvh.stack = f.stack;
    bvh.sah_cost = order.empty() ? 0.0 : f.cost;
    bvh.order = std::move(order);
    return bvh;
}

namespace {
// A triangle as flatten_triangles gives it: v0 and the edges e1 = v1 - v0, e2 = v2 - v0.
struct Edges {
    glm::vec3 v0, e1, e2;
};
Edges edges_of(const TriangleSoup& soup, int t) {
    const glm::vec3* p = &soup.positions[3 * static_cast<size_t>(t)];
    return {p[0], p[1] - p[0], p[2] - p[0]};
}
} // namespace

std::vector<etk::float4> flatten_triangles(const TriangleSoup& soup,
                                           const std::vector<int>& order) {
    if (order.empty()) // device buffers cannot be empty: one all-zero triangle, never hit
        return std::vector<etk::float4>(3, etk::make_float4(0.0f, 0.0f, 0.0f, 0.0f));
    std::vector<etk::float4> out(3 * order.size());
    for (size_t i = 0; i < order.size(); ++i) {
        const Edges t = edges_of(soup, order[i]);
        out[3 * i] = etk::make_float4(t.v0.x, t.v0.y, t.v0.z, 0.0f);
        out[3 * i + 1] = etk::make_float4(t.e1.x, t.e1.y, t.e1.z, 0.0f);
        out[3 * i + 2] = etk::make_float4(t.e2.x, t.e2.y, t.e2.z, 0.0f);
    }
    return out;
}

std::vector<etk::float4> face_normals(const TriangleSoup& soup, const std::vector<int>& order) {
    if (order.empty()) // device buffers cannot be empty
        return std::vector<etk::float4>(1, etk::make_float4(0.0f, 0.0f, 0.0f, 0.0f));
    std::vector<etk::float4> out(order.size());
    for (size_t i = 0; i < order.size(); ++i) {
        const glm::vec3 n = unit_face_normal(&soup.positions[3 * static_cast<size_t>(order[i])]);
        out[i] = etk::make_float4(n.x, n.y, n.z, 0.0f);
    }
    return out;
}

void append_packet(const TriangleSoup& soup, const std::vector<int>& order, const int lanes[4],
                   std::vector<etk::float4>& out) {
    float v[ETK_BVH_PACKET][4];
    for (int k = 0; k < 4; ++k) {
        glm::vec3 t[3] = {glm::vec3(0.0f), glm::vec3(0.0f), glm::vec3(0.0f)}; // unused: det 0
        if (lanes[k] >= 0)
            for (int c = 0; c < 3; ++c)
                t[c] = soup.positions[3 * static_cast<size_t>(order[lanes[k]]) + c];
        const float row[ETK_BVH_PACKET] = {
            t[0].x, t[0].y, t[0].z, t[1].x, t[1].y,
            t[1].z, t[2].x, t[2].y, t[2].z, as_float_bits(static_cast<uint32_t>(lanes[k]))};
        for (int r = 0; r < ETK_BVH_PACKET; ++r)
            v[r][k] = row[r];
    }
    for (int r = 0; r < ETK_BVH_PACKET; ++r)
        out.push_back(etk::make_float4(v[r][0], v[r][1], v[r][2], v[r][3]));
}

std::vector<etk::float4> flatten_packets(const TriangleSoup& soup, const Bvh& bvh,
                                         std::vector<int>* slots) {
    std::vector<etk::float4> out;
    if (slots)
        slots->assign(std::max<size_t>(bvh.order.size(), 1), 0);
    for (const auto& [first, count] : bvh.leaves)
        for (int b = 0; b < count; b += 4) {
            const int packet = static_cast<int>(out.size() / ETK_BVH_PACKET);
            int lanes[4];
            for (int k = 0; k < 4; ++k) {
                lanes[k] = b + k < count ? first + b + k : -1;
                if (slots && lanes[k] >= 0)
                    (*slots)[static_cast<size_t>(lanes[k])] = 4 * packet + k;
            }
            append_packet(soup, bvh.order, lanes, out);
        }
    if (out.empty()) { // device buffers cannot be empty: one packet of unused lanes
        const int none[4] = {-1, -1, -1, -1};
        append_packet(soup, bvh.order, none, out);
    }
    return out;
}

} // namespace et
