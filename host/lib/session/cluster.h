// The ranks of one render under mpirun (Open MPI), or a single process. Only this file's source
// includes MPI: when envtrace is built with it (ENVTRACE_MPI) and started by mpirun, the
// ranks render disjoint sample indices of one film and rank 0 writes the outputs; otherwise
// every call here is the trivial one of a cluster of one.
//
// Every collective below is entered by every rank, in the same order. Errors are collective
// too: a rank that fails passes its message to check(), which throws ClusterError on every
// rank, the message (on rank 0) naming each failed rank, its host and its cause.
#pragma once
#include "render/film_sums.h"
#include "util/error.h"

#include <cstdint>
#include <string>

namespace et {

// A failure of one or more ranks; what() is empty on the ranks that do not report it.
class ClusterError : public Error {
  public:
    using Error::Error;
};

class Cluster {
  public:
    // Starts MPI when this process is a rank of an mpirun (its environment says so) and the
    // build has MPI; a process started any other way is a cluster of one and never touches MPI.
    Cluster(int* argc, char*** argv);
    ~Cluster();
    Cluster(const Cluster&) = delete;
    Cluster& operator=(const Cluster&) = delete;

    int rank() const { return rank_; }
    int size() const { return size_; }
    bool root() const { return rank_ == 0; }
    // "rank 1 of 4 (host)" for messages.
    std::string describe(int rank) const;
    // True when started by mpirun with more than one rank but built without MPI (each rank
    // would render the whole image alone): the render command refuses that.
    bool launched_without_mpi() const { return launched_without_mpi_; }

    // Every rank passes its error ("" if none); when any failed, throws ClusterError on every
    // rank: on rank 0 it lists "rank R of N (host): error" for each failed rank.
    void check(const std::string& error) const;
    // Rank 0's value on every rank.
    int64_t broadcast(int64_t value) const;
    // The largest of every rank's values, element-wise, on every rank.
    void max_all(int64_t* values, int n) const;
    // The sum of every rank's values on rank 0 (others' arrays unchanged).
    void sum_to_root(uint64_t* values, int n) const;
    // The sum of every rank's film on rank 0 (exact, so the order does not matter); an empty
    // film on the other ranks. In slices, so that MPI's buffers stay small.
    FilmSums reduce(const FilmSums& mine) const;

  private:
    int rank_ = 0, size_ = 1;
    bool mpi_ = false, launched_without_mpi_ = false;
    std::string host_;
};

// The message of the exception in flight, as main prints it (for Cluster::check).
std::string error_text();

// Runs f, returning its error message ("" when it succeeded): a rank's part of Cluster::check.
template <class F> std::string attempt(F&& f) {
    try {
        f();
        return "";
    } catch (...) {
        return error_text();
    }
}

} // namespace et
