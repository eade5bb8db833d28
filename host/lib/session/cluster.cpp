#include "session/cluster.h"
#include "opencl/opencl_runtime.h"

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <thread>
#include <unistd.h>
#include <vector>

#ifdef ENVTRACE_HAVE_MPI
#include <mpi.h>
#endif

namespace et {
namespace {

// The world size mpirun (Open MPI, or a PMI launcher) announces to its ranks; 0 if none.
int launcher_world_size() {
    for (const char* var : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE"})
        if (const char* v = std::getenv(var))
            return std::max(0, std::atoi(v));
    return std::getenv("PMIX_RANK") ? 1 : 0;
}

#ifdef ENVTRACE_HAVE_MPI
// Waits for a request without spinning: a rank that finished its pass early would otherwise
// poll (and, oversubscribed, sched_yield) at full speed, taking a core from the ranks still
// rendering. Small messages only: MPI progresses between the tests.
void wait_idle(MPI_Request& request) {
    for (int tests = 0;; ++tests) {
        int done = 0;
        MPI_Test(&request, &done, MPI_STATUS_IGNORE);
        if (done)
            return;
        if (tests > 50)
            std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
}

// Every rank has arrived (idle wait): what follows runs without ranks waiting long in it.
void arrive_all() {
    MPI_Request r;
    MPI_Ibarrier(MPI_COMM_WORLD, &r);
    wait_idle(r);
}

void add_pixels_op(void* in, void* inout, int* len, MPI_Datatype*) {
    FilmSums::add_pixels(static_cast<FilmSums::Pixel*>(inout),
                         static_cast<const FilmSums::Pixel*>(in), static_cast<size_t>(*len));
}

void add_aov_pixels_op(void* in, void* inout, int* len, MPI_Datatype*) {
    add_aov_pixels(static_cast<AovPixel*>(inout), static_cast<const AovPixel*>(in),
                   static_cast<size_t>(*len));
}

// Sums `n` elements of `T` (bytes) from every rank into rank 0's `out`, in slices of 64k, with
// the commutative operator `fn` (integer sums and flag unions).
template <class T>
void reduce_pixels(const T* mine, T* out, size_t n, MPI_User_function* fn, int rank) {
    MPI_Datatype type;
    MPI_Type_contiguous(static_cast<int>(sizeof(T)), MPI_BYTE, &type);
    MPI_Type_commit(&type);
    MPI_Op op;
    MPI_Op_create(fn, 1, &op);
    constexpr size_t kSlice = size_t(1) << 16; // pixels per message: 7-8 MiB
    for (size_t first = 0; first < n; first += kSlice) {
        const int k = static_cast<int>(std::min(kSlice, n - first));
        MPI_Reduce(mine + first, rank == 0 ? out + first : nullptr, k, type, op, 0, MPI_COMM_WORLD);
    }
    MPI_Op_free(&op);
    MPI_Type_free(&type);
}
#endif

} // namespace

Cluster::Cluster(int* argc, char*** argv) {
    char host[256] = {};
    gethostname(host, sizeof host - 1);
    host_ = host;
    const int announced = launcher_world_size();
#ifdef ENVTRACE_HAVE_MPI
    if (announced > 0) {
        int provided = 0;
        // The native back end runs threads, but only this one calls MPI.
        MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided);
        mpi_ = true;
        MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
        MPI_Comm_size(MPI_COMM_WORLD, &size_);
    }
#else
    (void)argc;
    (void)argv;
    launched_without_mpi_ = announced > 1;
#endif
}

Cluster::~Cluster() {
#ifdef ENVTRACE_HAVE_MPI
    if (mpi_)
        MPI_Finalize();
#endif
}

std::string Cluster::describe(int rank) const {
    return "rank " + std::to_string(rank) + " of " + std::to_string(size_);
}

void Cluster::check(const std::string& error) const {
    if (!mpi_) {
        if (!error.empty())
            throw Error(error);
        return;
    }
#ifdef ENVTRACE_HAVE_MPI
    const std::string mine = error.empty() ? "" : describe(rank_) + " (" + host_ + "): " + error;
    int failed = mine.empty() ? 0 : 1, any = 0;
    MPI_Request r;
    MPI_Iallreduce(&failed, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD, &r);
    wait_idle(r);
    if (!any)
        return;
    const int len = static_cast<int>(mine.size());
    std::vector<int> lens(rank_ == 0 ? size_ : 0), offsets(lens.size());
    MPI_Gather(&len, 1, MPI_INT, lens.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
    std::string all;
    if (rank_ == 0) {
        int total = 0;
        for (int r = 0; r < size_; ++r) {
            offsets[r] = total;
            total += lens[r];
        }
        all.resize(static_cast<size_t>(total));
    }
    MPI_Gatherv(mine.data(), len, MPI_CHAR, all.data(), lens.data(), offsets.data(), MPI_CHAR, 0,
                MPI_COMM_WORLD);
    if (rank_ != 0)
        throw ClusterError("");
    std::string message;
    for (int r = 0; r < size_; ++r) {
        if (lens[r] == 0)
            continue;
        if (!message.empty())
            message += "\nenvtrace: error: ";
        message += all.substr(static_cast<size_t>(offsets[r]), static_cast<size_t>(lens[r]));
    }
    throw ClusterError(message);
#endif
}

int64_t Cluster::broadcast(int64_t value) const {
#ifdef ENVTRACE_HAVE_MPI
    if (mpi_) {
        MPI_Request r;
        MPI_Ibcast(&value, 1, MPI_INT64_T, 0, MPI_COMM_WORLD, &r);
        wait_idle(r);
    }
#endif
    return value;
}

void Cluster::max_all(int64_t* values, int n) const {
#ifdef ENVTRACE_HAVE_MPI
    if (mpi_) {
        MPI_Request r;
        MPI_Iallreduce(MPI_IN_PLACE, values, n, MPI_INT64_T, MPI_MAX, MPI_COMM_WORLD, &r);
        wait_idle(r);
    }
#else
    (void)values;
    (void)n;
#endif
}

void Cluster::sum_to_root(uint64_t* values, int n) const {
#ifdef ENVTRACE_HAVE_MPI
    if (mpi_)
        MPI_Reduce(rank_ == 0 ? MPI_IN_PLACE : values, values, n, MPI_UINT64_T, MPI_SUM, 0,
                   MPI_COMM_WORLD);
#else
    (void)values;
    (void)n;
#endif
}

FilmSums Cluster::reduce(const FilmSums& mine) const {
    if (!mpi_)
        return mine;
#ifdef ENVTRACE_HAVE_MPI
    FilmSums out = rank_ == 0 ? FilmSums(mine.width(), mine.height(), mine.has_aovs()) : FilmSums();
    arrive_all();
    reduce_pixels(mine.data(), rank_ == 0 ? out.data() : nullptr, mine.pixels(), &add_pixels_op,
                  rank_);
    if (mine.has_aovs()) // every rank has them or none: the render key covers --aovs
        reduce_pixels(mine.aov_data(), rank_ == 0 ? out.aov_data() : nullptr, mine.pixels(),
                      &add_aov_pixels_op, rank_);
    return out;
#else
    return mine;
#endif
}

std::string error_text() {
    try {
        throw;
    } catch (const cl::Error& e) {
        return std::string("OpenCL call ") + e.what() + " failed: " + cl_error_name(e.err());
    } catch (const std::bad_alloc&) {
        return "out of memory (a smaller film, fewer --paths or a smaller scene needs less)";
    } catch (const std::exception& e) {
        return e.what();
    } catch (...) {
        return "unexpected exception (not a std::exception)";
    }
}

} // namespace et
