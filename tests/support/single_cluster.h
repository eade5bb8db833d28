// The cluster of a test process outside mpirun: one rank, which never touches MPI. Shared by the
// session tests, which need one to make a RenderSession.
#pragma once
#include "session/cluster.h"

namespace ett {

inline const et::Cluster& single_cluster() {
    static int argc = 0;
    static char** argv = nullptr;
    static const et::Cluster cluster(&argc, &argv);
    return cluster;
}

} // namespace ett
