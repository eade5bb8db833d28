// The cost of the film's reduction across MPI ranks (host/lib/session/cluster.h, Cluster::reduce)
// and of adding one pass to the exact sums (FilmSums::add_pass), for films of 512x512 to 4096x4096.
// Run under mpirun (rank 0 prints one JSON line per size); alone it measures add_pass only.
//   mpirun -np 2 build/tools/bench/film_reduce [--runs R] [--sizes 512,1024,2048,4096]
#include "session/cluster.h"
#include "render/film.h"
#include "render/film_sums.h"
#include "util/timer.h"

#include <mpi.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

namespace {

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

} // namespace

int main(int argc, char** argv) {
    et::Cluster cluster(&argc, &argv);
    int runs = 5;
    std::vector<int> sizes = {512, 1024, 2048, 4096};
    for (int i = 1; i + 1 < argc; i += 2) {
        if (!std::strcmp(argv[i], "--runs"))
            runs = std::max(1, std::atoi(argv[i + 1]));
        if (!std::strcmp(argv[i], "--sizes")) {
            sizes.clear();
            std::stringstream ss(argv[i + 1]);
            for (std::string t; std::getline(ss, t, ',');)
                sizes.push_back(std::atoi(t.c_str()));
        }
    }
    for (int n : sizes) {
        // A pass of pseudo-random radiance (wide range, as a frame has), added to the sums twice
        // so that they hold something; add_pass timed on every rank, rank 0's printed.
        et::Film pass(n, n);
        uint32_t x = 12345u + static_cast<uint32_t>(cluster.rank());
        for (size_t i = 0; i < pass.pixels(); ++i) {
            x = x * 1664525u + 1013904223u;
            const float v = float(x >> 8) * (1.0f / 16777216.0f) * float(1 << (x & 7));
            pass.film_sum[i] = etk::make_float4(v, 0.5f * v, 0.25f * v, 1.0f);
            pass.film_sq[i] = etk::make_float4(v * v, 0.25f * v * v, 0.0625f * v * v, 0.0f);
        }
        et::FilmSums sums(n, n);
        std::vector<double> add_s, reduce_s;
        for (int r = 0; r < runs; ++r) {
            et::Timer t;
            sums.add_pass(pass);
            add_s.push_back(t.seconds());
        }
        for (int r = 0; r < runs && cluster.size() > 1; ++r) {
            MPI_Barrier(MPI_COMM_WORLD);
            et::Timer t;
            const et::FilmSums total = cluster.reduce(sums);
            reduce_s.push_back(t.seconds()); // rank 0: until the sum is complete there
        }
        if (cluster.root())
            std::printf("{\"width\": %d, \"height\": %d, \"ranks\": %d, \"bytes_per_rank\": %zu, "
                        "\"add_pass_s\": %.6f, \"reduce_s\": %.6f}\n",
                        n, n, cluster.size(), sums.pixels() * sizeof(et::FilmSums::Pixel),
                        median(add_s), reduce_s.empty() ? 0.0 : median(reduce_s));
        std::fflush(stdout);
    }
    return 0;
}
