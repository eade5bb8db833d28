// Bad input never crashes and never yields NaN: every problem file gives a one-line et::Error
// naming it (or loads with sanitised texels and a warning), in the library and through the CLI.
#include "render/env_sampling.h"
#include "kernels/sampler.h"
#include "cli_run.h"
#include "test_data.h"

#include <OpenImageIO/imageio.h>

#include <gtest/gtest.h>

#include <cstdio>
#include <sys/resource.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {

// Loads `path`: an et::Error must be one line naming the file; a loaded map must be valid.
void expect_clean_outcome(const std::string& path) {
    SCOPED_TRACE(path);
    ett::WarningCapture warnings;
    try {
        const et::EnvMap env = et::load_envmap(path, {});
        for (float v : env.image.rgb)
            ASSERT_TRUE(std::isfinite(v) && v >= 0.0f);
        for (float v : env.dist.table)
            ASSERT_TRUE(std::isfinite(v) && v >= 0.0f);
        std::vector<float> u;
        for (int i = 0; i < 1024; ++i) {
            const etk::float2 x = etk::etk_sample_pair(ETK_SAMPLER_SOBOL, 1, 0, i, 0);
            u.push_back(x.x), u.push_back(x.y);
        }
        for (const auto& s : et::sample_env_host(env, u)) {
            ASSERT_TRUE(std::isfinite(s.pdf) && s.pdf >= 0.0f);
            ASSERT_EQ(s.pdf > 0.0f, env.dist.has_light());
            for (int c = 0; c < 3; ++c)
                ASSERT_TRUE(std::isfinite(s.radiance[c]) && std::isfinite(s.dir[c]));
        }
    } catch (const et::Error& e) {
        const std::string m = e.what();
        EXPECT_EQ(m.find('\n'), std::string::npos) << "not one line: " << m;
        EXPECT_NE(m.find(path), std::string::npos) << "does not name the file: " << m;
    }
}

void expect_error(const std::string& path, const std::string& what) {
    try {
        et::load_envmap(path, {});
        ADD_FAILURE() << path << ": loaded, expected an error (" << what << ")";
    } catch (const et::Error& e) {
        const std::string m = e.what();
        EXPECT_EQ(m.find('\n'), std::string::npos) << m;
        EXPECT_NE(m.find(path), std::string::npos) << m;
    }
}

void write_bytes(const std::string& path, const std::string& bytes) {
    std::ofstream(path, std::ios::binary) << bytes;
}

std::string be32(uint32_t v) {
    return std::string{char(v >> 24), char(v >> 16), char(v >> 8), char(v)};
}

std::string png_chunk(const std::string& type, const std::string& data) {
    const std::string td = type + data;
    uint32_t crc = 0xffffffffu;
    for (unsigned char c : td) {
        crc ^= c;
        for (int k = 0; k < 8; ++k)
            crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
    }
    return be32(static_cast<uint32_t>(data.size())) + td + be32(~crc);
}

// An 8-bit PNG (colour type 0 grey, 2 RGB) whose header declares w x h pixels and whose data is a
// zlib stream of one stored (uncompressed) deflate block of 5000 zero bytes: far less than the
// pixels it declares.
std::string png_declaring(uint32_t w, uint32_t h, char colour_type) {
    const std::string ihdr = be32(w) + be32(h) + std::string{8, colour_type, 0, 0, 0};
    std::string idat = "\x78\x01";
    idat += std::string{1, char(5000 & 0xff), char(5000 >> 8), char(~5000 & 0xff),
                        char((~5000 >> 8) & 0xff)};
    idat += std::string(5000, '\0');
    idat += be32(0x1387138d); // adler32 of the zeros is not checked before the size
    return "\x89PNG\r\n\x1a\n" + png_chunk("IHDR", ihdr) + png_chunk("IDAT", idat) +
           png_chunk("IEND", "");
}

// Resident memory of this process in bytes: now ("VmRSS") or at its peak ("VmHWM").
int64_t proc_status_bytes(const char* key) {
    std::ifstream f("/proc/self/status");
    std::string line;
    const std::string k = std::string(key) + ":";
    while (std::getline(f, line))
        if (line.rfind(k, 0) == 0)
            return std::atoll(line.c_str() + k.size()) * 1024; // "VmRSS:   1234 kB"
    return -1;
}

TEST(EnvmapBadInput, MissingZeroByteDirectoryCorrupt) {
    const std::string dir = ett::scratch_dir("bad-input");
    expect_error(dir + "/missing.hdr", "missing");
    write_bytes(dir + "/empty.exr", "");
    expect_error(dir + "/empty.exr", "zero bytes");
    fs::create_directories(dir + "/folder.hdr");
    expect_error(dir + "/folder.hdr", "directory");
    std::string garbage;
    for (int i = 0; i < 4096; ++i)
        garbage.push_back(static_cast<char>((i * 2654435761u) >> 13));
    write_bytes(dir + "/garbage.exr", garbage);
    write_bytes(dir + "/garbage.hdr", garbage);
    write_bytes(dir + "/truncated.hdr", "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 128 +X 256\n");
    expect_error(dir + "/garbage.exr", "corrupt");
    expect_error(dir + "/garbage.hdr", "corrupt");
    expect_error(dir + "/truncated.hdr", "truncated");
}

TEST(EnvmapBadInput, Unreadable) {
    const std::string dir = ett::scratch_dir("unreadable");
    const std::string path = dir + "/locked.exr";
    et::write_image(path, 8, 4, 3, std::vector<float>(8 * 4 * 3, 1.0f));
    ASSERT_EQ(chmod(path.c_str(), 0), 0);
    if (access(path.c_str(), R_OK) == 0) {
        // Root reads anything: the file loads, which is also a clean outcome.
        expect_clean_outcome(path);
        GTEST_SKIP() << "running as root: chmod 000 does not stop reads (clean load checked)";
    }
    expect_error(path, "unreadable");
}

TEST(EnvmapBadInput, NonFiniteAndNegativeTexelsWarnOnce) {
    et::RgbImage img = ett::constant_image(16, 8, 1.0f);
    img.at(1, 1)[0] = NAN;
    img.at(2, 2)[1] = INFINITY;
    img.at(3, 3)[2] = -INFINITY;
    img.at(4, 4)[0] = -5.0f;
    const std::string path = ett::scratch_dir("nan") + "/nan.exr";
    ett::write_raw_exr(path, 16, 8, img.rgb);
    ett::WarningCapture w;
    const et::EnvMap env = et::load_envmap(path, {});
    EXPECT_EQ(w.count_containing("3 non-finite and 1 negative"), 1u);
    EXPECT_EQ(w.messages().size(), 1u);
    expect_clean_outcome(path);
}

TEST(EnvmapBadInput, DwabNegativeRingingWarnsOnceAndSamplesFine) {
    ETT_DATA_FILE(path, "envmaps/esplanade_512_dwab.exr");
    ett::WarningCapture w;
    const et::EnvMap env = et::load_envmap(path, {});
    ASSERT_EQ(w.messages().size(), 1u);
    EXPECT_NE(w.messages()[0].find("negative"), std::string::npos) << w.messages()[0];
    for (float v : env.image.rgb)
        ASSERT_TRUE(std::isfinite(v) && v >= 0.0f);
    et::EnvSamplerCL cl(ett::runtime(), env);
    for (const auto& s : cl.sample_sequence(ETK_SAMPLER_SOBOL, 3, 0, 0, 1 << 16)) {
        ASSERT_TRUE(s.pdf > 0.0f && std::isfinite(s.pdf));
        for (int c = 0; c < 3; ++c)
            ASSERT_TRUE(std::isfinite(s.radiance[c]) && s.radiance[c] >= 0.0f);
    }
}

TEST(EnvmapBadInput, AllBlackMapIsValidNoLight) {
    ett::WarningCapture w;
    const et::EnvMap env = et::make_envmap("black", ett::constant_image(32, 16, 0.0f), {});
    EXPECT_FALSE(env.dist.has_light());
    EXPECT_EQ(w.count_containing("black everywhere"), 1u);
    for (float v : env.dist.table)
        ASSERT_TRUE(std::isfinite(v));
    et::EnvSamplerCL cl(ett::runtime(), env);
    for (const auto& s : cl.sample_sequence(ETK_SAMPLER_RANDOM, 3, 0, 0, 4096)) {
        ASSERT_EQ(s.pdf, 0.0f);
        for (int c = 0; c < 3; ++c) {
            ASSERT_EQ(s.radiance[c], 0.0f);
            ASSERT_TRUE(std::isfinite(s.dir[c]));
        }
        EXPECT_EQ(etk::etk_env_pdf(env.dist.table.data(), env.desc(),
                                   etk::make_float3(s.dir[0], s.dir[1], s.dir[2])),
                  0.0f);
    }
}

TEST(EnvmapBadInput, OneByOneAndNon2to1WarnAndWork) {
    const std::string dir = ett::scratch_dir("shapes");
    et::write_image(dir + "/one.exr", 1, 1, 3, {2.0f, 1.0f, 0.5f});
    et::write_image(dir + "/square.hdr", 8, 8, 3, std::vector<float>(8 * 8 * 3, 0.3f));
    for (const char* name : {"/one.exr", "/square.hdr"}) {
        ett::WarningCapture w;
        const et::EnvMap env = et::load_envmap(dir + name, {});
        EXPECT_EQ(w.count_containing("not a 2:1"), 1u) << name;
        EXPECT_TRUE(env.dist.has_light());
        expect_clean_outcome(dir + name);
    }
}

TEST(EnvmapBadInput, EveryEdgeCaseImage) {
    const std::string dir = ett::data_file("edge-cases/images");
    if (dir.empty())
        GTEST_SKIP() << "edge-cases/images not found: set ENVTRACE_DATA to ../shared/data";
    int n = 0;
    for (const auto& entry : fs::directory_iterator(dir)) {
        expect_clean_outcome(entry.path().string());
        ++n;
    }
    EXPECT_GT(n, 5);
}

// Runs build/envtrace with `args`; returns its wait status, stderr in `err`.
int run_cli(const std::vector<std::string>& args, std::string& err) {
    const ett::CliRun r = ett::run_envtrace(args, ett::scratch_dir("cli-err"));
    err = r.err;
    return r.status;
}

TEST(EnvmapBadInput, CliRejectsBadMapsWithOneLine) {
    const std::string dir = ett::scratch_dir("cli");
    write_bytes(dir + "/garbage.hdr", std::string(1000, '\x7f'));
    write_bytes(dir + "/empty.exr", "");
    fs::create_directories(dir + "/folder.exr");
    for (const std::string& bad :
         {dir + "/missing.exr", dir + "/garbage.hdr", dir + "/empty.exr", dir + "/folder.exr"}) {
        const std::string out = dir + "/points.png";
        std::string err;
        const int status = run_cli({"sample", bad, "-n", "16", "-o", out}, err);
        ASSERT_TRUE(WIFEXITED(status)) << bad << ": killed by signal " << WTERMSIG(status);
        EXPECT_NE(WEXITSTATUS(status), 0) << bad;
        EXPECT_EQ(err.rfind("envtrace: error: ", 0), 0u) << err;
        EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
        EXPECT_NE(err.find(bad), std::string::npos) << err;
        EXPECT_FALSE(fs::exists(out)) << bad;
        for (const auto& e : fs::directory_iterator(dir))
            EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
    }
}

TEST(EnvmapBadInput, CliSamplesDwabMapWithOneWarning) {
    ETT_DATA_FILE(path, "envmaps/esplanade_512_dwab.exr");
    const std::string out = ett::scratch_dir("cli-dwab") + "/points.png";
    std::string err;
    const int status = run_cli({"sample", path, "-n", "64", "-o", out}, err);
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 0) << err;
    EXPECT_EQ(err.rfind("envtrace: warning: ", 0), 0u) << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
    EXPECT_TRUE(fs::exists(out));
}

// Headers that declare more pixels than can be held, or than their file can hold, are refused
// before any pixel is allocated: checked in a child whose address space is capped at 1 GiB more
// than it uses (the old reader allocated 3.7 GB for a 60-byte HDR, 5.3 GB for a 5 kB PNG).
TEST(EnvmapBadInputDeathTest, HugeDeclaredSizesAreRefusedBeforeAllocating) {
    GTEST_FLAG_SET(death_test_style, "threadsafe");
    const std::string dir = ett::scratch_dir("huge-header");
    write_bytes(dir + "/huge.hdr", "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 12500 +X 25000\n");
    write_bytes(dir + "/claims.hdr", "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 8000 +X 16000\n");
    write_bytes(dir + "/huge.pfm", "PF\n30000 15000\n-1.0\n" + std::string(64, '\0'));
    // A PNG claiming 30000x15000 RGB with 5 kB of (compressed zero) data.
    write_bytes(dir + "/huge.png", png_declaring(30000, 15000, 2));
    for (const char* name : {"huge.hdr", "claims.hdr", "huge.pfm", "huge.png"}) {
        const std::string path = dir + "/" + name;
        SCOPED_TRACE(path);
        EXPECT_EXIT(
            {
                long pages = 0;
                if (FILE* f = std::fopen("/proc/self/statm", "r")) {
                    if (std::fscanf(f, "%ld", &pages) != 1)
                        pages = 0;
                    std::fclose(f);
                }
                rlimit lim{};
                getrlimit(RLIMIT_AS, &lim);
                lim.rlim_cur = static_cast<rlim_t>(pages) * sysconf(_SC_PAGESIZE) + (1L << 30);
                setrlimit(RLIMIT_AS, &lim);
                et::set_warning_sink([](const std::string&) {});
                try {
                    et::load_envmap(path, {});
                    std::_Exit(2); // loaded
                } catch (const et::Error& e) {
                    const std::string m = e.what();
                    const bool named = m.rfind(path, 0) == 0 && m.find('\n') == std::string::npos;
                    const bool says = m.find("budget") != std::string::npos ||
                                      m.find("corrupt or truncated") != std::string::npos;
                    std::_Exit(named && says ? 0 : 3);
                } catch (...) {
                    std::_Exit(4); // bad_alloc: it allocated first
                }
            },
            ::testing::ExitedWithCode(0), "");
    }
}

// Fuzz finding F7: a header may declare a size within the budget and the 100000:1 bound that its
// file cannot hold (a 5 kB grey PNG declaring 16000x8000 pixels: 1.5 GB of float texels and a
// 1 GB distribution). The texels grow as bands decode and the distribution's table is allocated
// after the first band, so the load fails on the missing data having touched a few megabytes,
// not the declared size (it touched 3 GB and more before). Measured as the peak resident memory
// of a child process, on every path that reads a map.
TEST(EnvmapBadInputDeathTest, DeclaredSizeBeyondTheDataFailsBeforeTouchingIt) {
    GTEST_FLAG_SET(death_test_style, "threadsafe");
    const std::string path = ett::scratch_dir("declared-size") + "/claims.png";
    write_bytes(path, png_declaring(16000, 8000, 0));
    for (int how = 0; how < 3; ++how) {
        SCOPED_TRACE(how == 0   ? "load_envmap, 2 threads"
                     : how == 1 ? "load_envmap, 1 thread"
                                : "read_rgb_image");
        EXPECT_EXIT(
            {
                et::set_warning_sink([](const std::string&) {});
                // Reset the peak to what is resident now (Linux 4.0+); where that is refused the
                // peak so far is that of a fresh test process, small as well.
                std::ofstream("/proc/self/clear_refs") << "5";
                const int64_t before = proc_status_bytes("VmRSS");
                int code = 2; // loaded
                try {
                    et::DistributionOptions opt;
                    opt.threads = how == 1 ? 1 : 2;
                    if (how < 2)
                        et::load_envmap(path, opt);
                    else
                        et::read_rgb_image(path);
                } catch (const et::Error& e) {
                    const std::string m = e.what();
                    code = m.rfind(path, 0) == 0 && m.find('\n') == std::string::npos ? 0 : 3;
                } catch (...) {
                    code = 4;
                }
                const int64_t grew = proc_status_bytes("VmHWM") - before;
                if (code == 0 && (before < 0 || grew > (int64_t(256) << 20)))
                    code = 5; // touched (a good part of) the declared size
                std::_Exit(code);
            },
            ::testing::ExitedWithCode(0), "");
    }
}

// PFM is read here: corrupt files say what is wrong (OpenImageIO said 'unknown error'), both
// byte orders and grey PFMs read, and what write_image writes reads back bit for bit.
TEST(EnvmapBadInput, PfmReadWriteAndCorruption) {
    const std::string dir = ett::scratch_dir("pfm");
    auto error_of = [](const std::string& path) {
        return ett::error_of([&] { et::read_rgb_image(path); });
    };
    write_bytes(dir + "/short.pfm", "PF\n4 2\n-1.0\n" + std::string(10, '\0'));
    write_bytes(dir + "/header.pfm", "PF\nfour 2\n-1.0\n" + std::string(96, '\0'));
    write_bytes(dir + "/magic.pfm", "P6\n4 2\n255\n" + std::string(24, '\0'));
    write_bytes(dir + "/scale.pfm", "PF\n4 2\n0\n" + std::string(96, '\0'));
    write_bytes(dir + "/neg.pfm", "PF\n-4 2\n-1.0\n" + std::string(96, '\0'));
    EXPECT_NE(error_of(dir + "/short.pfm").find("truncated PFM"), std::string::npos);
    EXPECT_NE(error_of(dir + "/header.pfm").find("corrupt PFM header"), std::string::npos);
    EXPECT_NE(error_of(dir + "/magic.pfm").find("not a PFM file"), std::string::npos);
    EXPECT_NE(error_of(dir + "/scale.pfm").find("corrupt PFM header"), std::string::npos);
    EXPECT_NE(error_of(dir + "/neg.pfm").find("no pixels"), std::string::npos);
    for (const char* f : {"short", "header", "magic", "scale", "neg"})
        EXPECT_EQ(error_of(dir + "/" + f + ".pfm").find("unknown error"), std::string::npos);

    // Round trip, rows bottom to top.
    std::vector<float> px(5 * 3 * 3);
    for (size_t i = 0; i < px.size(); ++i)
        px[i] = 0.25f * static_cast<float>(i) - 3.0f;
    et::write_image(dir + "/rt.pfm", 5, 3, 3, px);
    const et::RgbImage img = et::read_rgb_image(dir + "/rt.pfm");
    ASSERT_EQ(img.width, 5);
    ASSERT_EQ(img.height, 3);
    EXPECT_EQ(img.rgb, px);
    // Big-endian grey: 2x1, values 1 and 2, bottom row first (one row here).
    write_bytes(dir + "/grey.pfm",
                std::string("Pf\n2 1\n1.0\n") + std::string("\x3f\x80\x00\x00\x40\x00\x00\x00", 8));
    const et::RgbImage g = et::read_rgb_image(dir + "/grey.pfm");
    EXPECT_EQ(g.rgb, (std::vector<float>{1, 1, 1, 2, 2, 2}));
    et::check_writable_format(dir + "/x.pfm");
    EXPECT_THROW(et::check_writable_format(dir + "/x.tga"), et::Error);
    EXPECT_THROW(et::check_writable_format(dir), et::Error);
}

// Distribution sizes in 64 bits: what the device cannot index is an error, not a 32-bit overflow
// and a read past the table; the blur is bounded.
TEST(EnvmapBadInput, DistributionSizeAndBlurBounds) {
    // Densities and CDFs, then the guide tables: 32768 + 1 for the marginal and for each row.
    EXPECT_EQ(et::distribution_table_entries(65536, 65536),
              2ull * 65536 + 1 + 65536ull * 131073 + 32769ull * 65537);
    EXPECT_THROW(et::check_distribution_size(65536, 65536), et::Error);
    EXPECT_THROW(et::check_distribution_size(46341, 46341), et::Error);
    EXPECT_THROW(et::check_distribution_size(65537, 1), et::Error);
    EXPECT_NO_THROW(et::check_distribution_size(65536, 1024));
    int w = 0, h = 0;
    EXPECT_THROW(et::parse_resolution("65536x65536", w, h), et::Error);
    EXPECT_THROW(et::parse_resolution("99999999999999999999x2", w, h), et::Error);
    et::DistributionOptions o;
    o.width = o.height = 65536;
    EXPECT_THROW(et::make_envmap("m", ett::constant_image(16, 8, 1.0f), o), et::Error);
    o = {};
    o.blur_sigma = 1e30f;
    EXPECT_THROW(et::make_envmap("m", ett::constant_image(16, 8, 1.0f), o), et::Error);
    o.blur_sigma = et::kMaxBlurSigma;
    const et::EnvMap env = et::make_envmap("m", ett::constant_image(16, 8, 1.0f), o);
    for (float v : env.dist.table)
        ASSERT_TRUE(std::isfinite(v));
}

// Texels beyond kMaxRadiance are clamped with one warning, and the intensity is bounded so that
// intensity x brightest texel stays at most kMaxRadiance.
TEST(EnvmapBadInput, HugeTexelsAndIntensityAreBounded) {
    ett::WarningCapture w;
    et::EnvMap env = et::make_envmap("bright", ett::constant_image(16, 8, 3e38f), {});
    EXPECT_EQ(w.count_containing("clamped"), 1u);
    EXPECT_EQ(env.max_texel, et::kMaxRadiance);
    for (float v : env.dist.table)
        ASSERT_TRUE(std::isfinite(v));
    env.scale = 1e20f;
    et::bound_intensity(env, "scene.json: environment.intensity");
    EXPECT_LE(double(env.scale) * env.max_texel, double(et::kMaxRadiance) * 1.0000001);
    EXPECT_EQ(w.count_containing("scene.json: environment.intensity"), 1u);
}

// A map so dim that the film's fixed-point sums cannot hold it (render/film_sums.h: 2^-70 units)
// says so, once; an ordinary one says nothing.
TEST(EnvmapBadInput, TooDimForTheFilmWarns) {
    ett::WarningCapture w;
    et::EnvMap dim = et::make_envmap("dim", ett::constant_image(16, 8, 1e-22f), {});
    et::bound_intensity(dim, "scene.json: environment.intensity");
    EXPECT_EQ(w.count_containing("below what the film holds"), 1u);
    et::EnvMap scaled = et::make_envmap("dim", ett::constant_image(16, 8, 1e-22f), {});
    scaled.scale = 1e12f; // the way out the warning gives
    et::bound_intensity(scaled, "scene.json: environment.intensity");
    et::EnvMap fine = et::make_envmap("fine", ett::constant_image(16, 8, 0.5f), {});
    et::bound_intensity(fine, "scene.json: environment.intensity");
    EXPECT_EQ(w.count_containing("below what the film holds"), 1u);
}

// A map of w x h texels spanning several decades, a third of it black, as float RGB.
std::vector<float> random_texels(int w, int h, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::vector<float> px(static_cast<size_t>(w) * h * 3);
    for (size_t p = 0; p < px.size(); p += 3) {
        const float s = u(rng) < 0.33f ? 0.0f : std::pow(10.0f, 5.0f * u(rng) - 2.0f);
        for (int c = 0; c < 3; ++c)
            px[p + c] = s * u(rng);
    }
    return px;
}

// load_envmap decodes the map in bands on one thread while the others build the distribution's
// blocks: the texels and the table must be exactly those of make_envmap(read_rgb_image(...)),
// whatever the thread count, the blur (its halo crosses bands) and the resampling.
TEST(EnvmapLoad, PipelinedLoadEqualsSequentialForAnyThreadCount) {
    const std::string dir = ett::scratch_dir("pipelined");
    const int w = 1200, h = 600; // three bands of decoding, three blocks of distribution rows
    const std::string path = dir + "/map.exr";
    ett::write_raw_exr(path, w, h, random_texels(w, h, 17));
    std::vector<et::DistributionOptions> variants(3);
    variants[1].blur_sigma = 3.0f;
    variants[2].blur_sigma = 0.0f;
    variants[2].width = 100;
    variants[2].height = 45;
    for (et::DistributionOptions opt : variants) {
        opt.threads = 1;
        const et::EnvMap ref = et::make_envmap(path, et::read_rgb_image(path), opt);
        for (int threads : {1, 2, 3, 8}) {
            SCOPED_TRACE("blur " + std::to_string(opt.blur_sigma) + ", " + std::to_string(threads) +
                         " threads");
            opt.threads = threads;
            const et::EnvMap env = et::load_envmap(path, opt);
            EXPECT_EQ(env.image.rgb, ref.image.rgb);
            EXPECT_EQ(env.dist.width, ref.dist.width);
            EXPECT_EQ(env.dist.table, ref.dist.table);
            EXPECT_EQ(env.dist.total, ref.dist.total);
            EXPECT_EQ(env.max_texel, ref.max_texel);
        }
    }
}

// A file that breaks off part-way is an et::Error naming it on every thread count: the threads
// waiting for rows that never come are released.
TEST(EnvmapLoad, TruncatedFileIsAnErrorOnAnyThreadCount) {
    const std::string dir = ett::scratch_dir("truncated");
    const int w = 1200, h = 600;
    const std::vector<float> px = random_texels(w, h, 5);
    for (const char* name : {"/cut.exr", "/cut.hdr"}) {
        const std::string path = dir + name;
        if (std::string(name) == "/cut.exr")
            ett::write_raw_exr(path, w, h, px);
        else
            et::write_image(path, w, h, 3, px);
        fs::resize_file(path, fs::file_size(path) * 3 / 5);
        for (int threads : {1, 2, 4}) {
            et::DistributionOptions opt;
            opt.threads = threads;
            try {
                et::load_envmap(path, opt);
                ADD_FAILURE() << path << " loaded on " << threads << " threads";
            } catch (const et::Error& e) {
                EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
            }
        }
    }
}

// Fuzz finding F6 as a file: a one-channel float TIFF of denormal texels loads with a finite,
// normalised distribution and samples fine.
TEST(EnvmapBadInput, GreyTiffOfDenormalsHasAFiniteDistribution) {
    const std::string path = ett::scratch_dir("f6") + "/grey.tif";
    const int w = 16, h = 8;
    std::vector<float> grey(w * h, 0.0f);
    for (int y = 0; y < 5; ++y)
        for (int x = 0; x < w; x += 4)
            grey[y * w + x] = 1.4013e-45f * (1 + 10 * x + 7 * y);
    auto out = OIIO::ImageOutput::create(path);
    ASSERT_TRUE(out);
    OIIO::ImageSpec spec(w, h, 1, OIIO::TypeDesc::FLOAT);
    spec.attribute("compression", "zip");
    ASSERT_TRUE(out->open(path, spec) && out->write_image(OIIO::TypeDesc::FLOAT, grey.data()) &&
                out->close())
        << out->geterror();
    const et::EnvMap env = et::load_envmap(path, {});
    EXPECT_TRUE(env.dist.has_light());
    EXPECT_TRUE(std::isfinite(env.dist.total));
    expect_clean_outcome(path);
}

// sanitize_texels checks blocks of texels at once (one vectorised unsigned max over their bits)
// and fixes the blocks that fail texel by texel: each bad texel counts once, in its first kind,
// the largest channel is found in clean and fixed blocks alike, and -0 is left as it is.
TEST(EnvmapBadInput, SanitizeCountsEachBadTexelOnceAndFindsTheMaximum) {
    et::RgbImage img = ett::constant_image(5000, 3, 0.5f); // several blocks of 4096 texels
    img.at(10, 0)[1] = -0.0f;
    img.at(4100, 0)[0] = NAN;
    img.at(4100, 0)[2] = -3.0f; // the same texel: non-finite only
    img.at(100, 1)[0] = INFINITY;
    img.at(7, 1)[2] = -1.0f;
    img.at(3000, 2)[1] = 7e11f;
    et::SanitizeReport r = et::sanitize_texels(img);
    EXPECT_EQ(r.non_finite, 2u);
    EXPECT_EQ(r.negative, 1u);
    EXPECT_EQ(r.too_bright, 0u);
    EXPECT_EQ(r.max_value, 7e11f);
    EXPECT_EQ(img.at(4100, 0)[0], 0.0f);
    EXPECT_EQ(img.at(4100, 0)[2], 0.0f);
    EXPECT_EQ(img.at(100, 1)[0], 0.0f);
    EXPECT_EQ(img.at(7, 1)[2], 0.0f);
    EXPECT_TRUE(img.at(10, 0)[1] == 0.0f && std::signbit(img.at(10, 0)[1]));
    img.at(4999, 2)[0] = 2e12f;
    r = et::sanitize_texels(img);
    EXPECT_EQ(r.non_finite + r.negative, 0u);
    EXPECT_EQ(r.too_bright, 1u);
    EXPECT_EQ(r.max_value, et::kMaxRadiance);
    EXPECT_EQ(img.at(4999, 2)[0], et::kMaxRadiance);
}

} // namespace
