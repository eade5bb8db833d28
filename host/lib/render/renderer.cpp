#include "render/renderer.h"

#include "util/error.h"
#include "render/wavefront_cl.h"
#include "render/wavefront_cpu.h"

namespace et {

std::unique_ptr<Renderer> make_renderer(const RendererOptions& o, const SceneArrays& arrays,
                                        const etk::EtkParams& params, ProgramBuildInfo* build) {
    if (o.backend == "opencl")
        return std::make_unique<WavefrontCL>(std::make_unique<ClRuntime>(o.device), arrays, params,
                                             o.paths, build);
    if (o.backend == "cpu")
        return std::make_unique<WavefrontCPU>(arrays, params, o.threads);
    throw Error("unknown back end '" + o.backend + "' (use opencl or cpu)");
}

} // namespace et
