// libFuzzer harness: a light-set JSON file (`envtrace render --lights`) through et::read_lights.
#include "fuzz_common.h"
#include "prepare/light_set.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
    etfuzz::silence_warnings();
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const etfuzz::FdCheck fds;
    const std::string path = etfuzz::write_file("lights.json", data, size);
    try {
        et::LightSet set = et::read_lights(path);
        // What the loader promises: a non-empty set of unit directions with finite powers >= 0.
        if (set.lights.empty())
            std::abort();
    } catch (const et::Error&) {
    }
    return 0;
}
