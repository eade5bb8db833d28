#include "render/render_state.h"

#include "opencl/kernel_sources.h"
#include "util/error.h"
#include "util/file_check.h"
#include "util/output_batch.h"

#include <xxhash.h>

#include <cstring>
#include <fstream>

namespace et {
namespace {

// File layout (little-endian, as written by this host): magic, then the header fields below, then
// the film's sums (FilmSums::Pixel per pixel, then AovPixel per pixel when the render keeps
// AOVs), then an XXH3 checksum of everything before it.
constexpr char kMagic[16] = {'e', 'n', 'v', 't', 'r', 'a', 'c',  'e',
                             '-', 's', 't', 'a', 't', 'e', '\n', 0};
// 2: exact sums (film_sums.h) and the first sample index; 3: the AOV flag and sums (film_aovs.h);
// 4: the render's total samples (3's reserved field; read as 0 from a version 3 state)
constexpr uint32_t kVersion = 4;
constexpr uint32_t kOldestVersion = 3;
constexpr uint32_t kByteOrder = 0x01020304;

struct Header {
    char magic[16];
    uint32_t version, byte_order;
    uint64_t key;
    int32_t width, height, spp, first;
    int32_t aovs, total; // aovs: 1 if AovPixel sums follow the film's; total: RenderState's
    uint64_t film_bytes;
};

uint64_t film_bytes(int width, int height, bool aovs) {
    return (sizeof(FilmSums::Pixel) + (aovs ? sizeof(AovPixel) : 0)) *
           static_cast<uint64_t>(width) * static_cast<uint64_t>(height);
}

class Hash {
  public:
    Hash() : s_(XXH3_createState()) {
        if (!s_)
            throw std::bad_alloc();
        XXH3_64bits_reset(s_);
    }
    ~Hash() { XXH3_freeState(s_); }
    void add(const void* data, size_t bytes) { XXH3_64bits_update(s_, data, bytes); }
    void add(const std::string& s) {
        add_value(static_cast<uint64_t>(s.size()));
        add(s.data(), s.size());
    }
    template <class T> void add_value(const T& v) { add(&v, sizeof v); }
    uint64_t digest() const { return XXH3_64bits_digest(s_); }

  private:
    XXH3_state_t* s_;
};

} // namespace

uint64_t render_key(const DeviceScene& scene) {
    Hash h;
    h.add(std::string("envtrace render key 1 " ENVTRACE_VERSION));
    h.add_value(static_cast<int32_t>(scene.settings.aovs)); // another film layout
    h.add(std::string(name_of(scene.settings.backend)));
    h.add_value(static_cast<int64_t>(scene.settings.device));
    for (const auto& [name, text] : embedded_kernel_sources()) { // a std::map: sorted
        h.add(name);
        h.add(text);
    }
    // The buffers are arrays of 4-byte scalars and float4: no padding bytes to hash.
#define ET_HASH_BUFFER(type, name)                                                                 \
    h.add(std::string(#name));                                                                     \
    h.add_value(static_cast<uint64_t>(scene.name.size()));                                         \
    h.add(scene.name.data(), scene.name.size() * sizeof(type));
    ETK_SCENE_BUFFERS(ET_HASH_BUFFER)
#undef ET_HASH_BUFFER
    etk::EtkParams p = scene.params; // 4-byte members only (kernels/params.h)
    p.sample_index = 0;
    p.first_pixel = 0;
    p.light_batch = 0; // where the map samples are drawn changes no bit of the film
    h.add_value(p);
    // The visibility strategy's schedule, decided on the host: which passes learn, and its
    // verdict's passes and cost (a verdict on one side of a resume and not on the other, or
    // weighed otherwise, would switch estimators part-way).
    if (scene.params.light_first == ETK_LIGHT_LEARNED) {
        const VisibilityOptions& o = scene.guide_options;
        h.add_value(static_cast<int32_t>(o.learning_passes));
        h.add_value(static_cast<int32_t>(o.verdict_passes));
        h.add_value(static_cast<int32_t>(o.verdict_after));
        h.add_value(static_cast<int32_t>(o.verdict_stride));
        h.add_value(verdict_cost_for(o, scene.params.guide_continuation != 0));
        if (o.fallback != Strategy::mis) // keys of the visibility strategy's states as before
            h.add_value(static_cast<int32_t>(o.fallback));
    }
    return h.digest();
}

void write_render_state(OutputBatch& batch, const std::string& path, const RenderState& state) {
    const FilmSums& f = state.sums;
    Header hd{};
    std::memcpy(hd.magic, kMagic, sizeof kMagic);
    hd.version = kVersion;
    hd.byte_order = kByteOrder;
    hd.key = state.key;
    hd.width = f.width();
    hd.height = f.height();
    hd.spp = state.spp;
    hd.first = state.first;
    hd.aovs = f.has_aovs() ? 1 : 0;
    hd.total = state.total;
    hd.film_bytes = film_bytes(f.width(), f.height(), f.has_aovs());
    batch.write(path, [&](const std::string& file) {
        std::ofstream out(file, std::ios::binary);
        Hash h;
        auto put = [&](const void* data, size_t bytes) {
            out.write(static_cast<const char*>(data), static_cast<std::streamsize>(bytes));
            h.add(data, bytes);
        };
        put(&hd, sizeof hd);
        put(f.data(), f.pixels() * sizeof(FilmSums::Pixel));
        if (f.has_aovs())
            put(f.aov_data(), f.pixels() * sizeof(AovPixel));
        const uint64_t sum = h.digest();
        out.write(reinterpret_cast<const char*>(&sum), sizeof sum);
        out.flush();
        out.close();
        if (!out)
            throw Error(path + ": cannot write the render state: " + std::strerror(errno));
    });
}

void write_render_state(const std::string& path, const RenderState& state) {
    OutputBatch batch({path}, {path});
    write_render_state(batch, path, state);
    batch.commit();
}

RenderState read_render_state(const std::string& path) {
    const uint64_t size = check_regular_file(path, uint64_t(1) << 40, "render state");
    const std::string bad = path + ": not an intact envtrace render state: ";
    Header hd{};
    if (size < sizeof hd + sizeof(uint64_t))
        throw Error(bad + "too short (" + byte_text(size) + ")");
    std::ifstream in(path, std::ios::binary);
    if (!in.read(reinterpret_cast<char*>(&hd), sizeof hd))
        throw Error(path + ": cannot read the render state");
    if (std::memcmp(hd.magic, kMagic, sizeof kMagic) != 0)
        throw Error(bad + "it does not start like one");
    if (hd.byte_order != kByteOrder)
        throw Error(bad + "written on a machine of the other byte order");
    if (hd.version < kOldestVersion || hd.version > kVersion)
        throw Error(bad + "format version " + std::to_string(hd.version) +
                    ", this envtrace reads " + std::to_string(kOldestVersion) + " to " +
                    std::to_string(kVersion) + " (written by another envtrace: render it again)");
    const int64_t end = int64_t(hd.first) + hd.spp;
    if (hd.width <= 0 || hd.height <= 0 || hd.width > 65536 || hd.height > 65536 || hd.spp < 0 ||
        hd.first < 0 || (hd.aovs != 0 && hd.aovs != 1) ||
        (hd.version == 3 ? hd.total != 0 : hd.total != 0 && hd.total < end) ||
        hd.film_bytes != film_bytes(hd.width, hd.height, hd.aovs == 1) ||
        size != sizeof hd + hd.film_bytes + sizeof(uint64_t))
        throw Error(bad + "its header does not match its size (" + byte_text(size) +
                    "): truncated or corrupt");
    RenderState st;
    st.key = hd.key;
    st.spp = hd.spp;
    st.first = hd.first;
    st.total = hd.total;
    st.sums = FilmSums(hd.width, hd.height, hd.aovs == 1);
    Hash h;
    h.add(&hd, sizeof hd);
    const uint64_t sum_bytes = st.sums.pixels() * sizeof(FilmSums::Pixel);
    in.read(reinterpret_cast<char*>(st.sums.data()), static_cast<std::streamsize>(sum_bytes));
    h.add(st.sums.data(), sum_bytes);
    if (st.sums.has_aovs()) {
        const uint64_t aov_bytes = st.sums.pixels() * sizeof(AovPixel);
        in.read(reinterpret_cast<char*>(st.sums.aov_data()),
                static_cast<std::streamsize>(aov_bytes));
        h.add(st.sums.aov_data(), aov_bytes);
    }
    uint64_t sum = 0;
    in.read(reinterpret_cast<char*>(&sum), sizeof sum);
    if (!in)
        throw Error(path + ": cannot read the render state (truncated while read?)");
    if (sum != h.digest())
        throw Error(bad + "its checksum does not match: corrupt");
    return st;
}

void check_render_state(const RenderState& state, const DeviceScene& scene,
                        const std::string& path) {
    if (state.sums.width() != scene.width() || state.sums.height() != scene.height())
        throw Error(path + ": the render state is of a " + std::to_string(state.sums.width()) +
                    "x" + std::to_string(state.sums.height()) + " film, this render is " +
                    std::to_string(scene.width()) + "x" + std::to_string(scene.height()));
    if (state.sums.has_aovs() != scene.settings.aovs)
        throw Error(path + ": the render state was saved " +
                    (state.sums.has_aovs() ? "with" : "without") + " AOVs, this render is " +
                    (scene.settings.aovs ? "with" : "without") + " (--aovs)");
    if (state.key != render_key(scene))
        throw Error(path + ": the render state is of another render: the scene, its inputs, the "
                           "settings (depth, strategy, heuristic, sampler, seed), the back end or "
                           "envtrace itself differ; resuming would not give the same image");
}

} // namespace et
