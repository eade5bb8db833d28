#include "commands.h"
#include "opencl/opencl_runtime.h"
#include "render/executor_cl.h"
#include "util/file_check.h"

#include <cstdio>
#include <iostream>
#include <string>

namespace et::cli {

void add_devices_command(CLI::App& app, Globals&) {
    auto* cmd = app.add_subcommand("devices", "List OpenCL platforms and devices");
    static bool kernels = false;
    cmd->add_flag("--kernels", kernels,
                  "Also build wavefront.cl on each device and list, per stage kernel, what the "
                  "device reports and the work-group size envtrace launches it with");
    cmd->callback([] {
        auto devices = list_devices();
        for (size_t i = 0; i < devices.size(); ++i) {
            const auto& d = devices[i];
            std::cout << "[" << i << "] " << d.device_name << "\n"
                      << "    platform: " << d.platform_name << "\n"
                      << "    device:   " << d.device_version << ", driver " << d.driver_version
                      << ", " << d.compute_units << " compute units\n";
            if (!kernels)
                continue;
            ClRuntime rt(static_cast<int>(i));
            const DeviceLimits& l = rt.limits();
            std::cout << "    memory:   " << byte_text(l.global_mem) << " global, largest buffer "
                      << byte_text(l.max_alloc) << (l.host_unified ? ", shared with the host" : "")
                      << "\n    floats:   "
                      << (l.correctly_rounded_div_sqrt
                              ? "x / y and sqrt correctly rounded, as on the host (built so)"
                              : "x / y and sqrt within OpenCL's ulp bounds only: images agree "
                                "with the native back end's statistically, not bit for bit")
                      << "\n    light samples: "
                      << (prefers_light_batches_on(l)
                              ? "in batches of " + std::to_string(ETK_LIGHT_BATCH) +
                                    " per work-item (a CPU; --light-batch auto)"
                              : std::string("one per shade work-item (not a CPU; --light-batch "
                                            "auto)"))
                      << "\n";
            std::cout << "    kernel          max group  preferred multiple  private bytes  "
                         "launched with\n";
            for (const StageKernelInfo& k : stage_kernel_info(rt)) {
                std::printf("    %-15s %9zu  %18zu  %13llu  %13zu\n", k.name.c_str(),
                            k.work_group_size, k.preferred_multiple,
                            static_cast<unsigned long long>(k.private_bytes), k.local);
            }
        }
    });
}

} // namespace et::cli
