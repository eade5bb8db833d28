// host/lib/image/image_io: round trips through every float format within its precision, sRGB
// decoding of 8-bit images, channel selection (grey replicated, RGBA and named channels), the
// write-to-temporary-then-rename promise and one-line et::Error messages naming the file.
#include "image/image_io.h"
#include "image/image_library.h"
#include "util/error.h"
#include "test_data.h"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <cstdint>
#include <sys/resource.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {

// Positive HDR values spanning several decades, deterministic.
std::vector<float> hdr_pixels(int w, int h, int channels, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> exponent(-3.0f, 4.0f);
    std::vector<float> px(static_cast<size_t>(w) * h * channels);
    for (float& v : px)
        v = std::pow(10.0f, exponent(rng));
    return px;
}

std::vector<std::string> files_in(const std::string& dir) {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir))
        names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

std::string read_all(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

// Writes a float image with the given channel names straight through OpenImageIO.
void write_named_channels(const std::string& path, int w, int h,
                          const std::vector<std::string>& names, const std::vector<float>& px) {
    auto out = OIIO::ImageOutput::create(path);
    ASSERT_TRUE(out) << OIIO::geterror();
    OIIO::ImageSpec spec(w, h, static_cast<int>(names.size()), OIIO::TypeDesc::FLOAT);
    spec.channelnames = names;
    spec.alpha_channel = -1;
    ASSERT_TRUE(out->open(path, spec)) << out->geterror();
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, px.data())) << out->geterror();
    ASSERT_TRUE(out->close()) << out->geterror();
}

// `call` must throw a one-line et::Error that names `path`.
template <class F> void expect_error_naming(const std::string& path, F call) {
    try {
        call();
        ADD_FAILURE() << path << ": no et::Error thrown";
    } catch (const et::Error& e) {
        const std::string m = e.what();
        EXPECT_NE(m.find(path), std::string::npos) << "does not name the file: " << m;
        EXPECT_EQ(m.find('\n'), std::string::npos) << "not one line: " << m;
    }
}

// A deflate stream (zlib) of stored blocks: valid for any inflater, no compression library needed.
std::string zlib_stored(const std::string& data) {
    std::string z = "\x78\x01";
    size_t at = 0;
    do {
        const size_t n = std::min<size_t>(65535, data.size() - at);
        const bool last = at + n == data.size();
        z += {char(last ? 1 : 0), char(n & 0xff), char(n >> 8), char(~n & 0xff),
              char((~n >> 8) & 0xff)};
        z += data.substr(at, n);
        at += n;
    } while (at < data.size());
    uint32_t a = 1, b = 0;
    for (unsigned char c : data) {
        a = (a + c) % 65521;
        b = (b + a) % 65521;
    }
    const uint32_t adler = b << 16 | a;
    z += {char(adler >> 24), char(adler >> 16), char(adler >> 8), char(adler)};
    return z;
}

// A little-endian TIFF of w x h pixels of `spp` 8-bit channels (contiguous; the first grey, the
// others extra samples), PhotometricInterpretation MinIsWhite (0), in zip (Adobe deflate) strips
// of `rps` rows. By hand: OpenImageIO's writer does not write MinIsWhite.
std::string miniswhite_tiff(int w, int h, int spp, int rps, const std::string& px) {
    auto le16 = [](uint32_t v) { return std::string{char(v), char(v >> 8)}; };
    auto le32 = [](uint32_t v) {
        return std::string{char(v), char(v >> 8), char(v >> 16), char(v >> 24)};
    };
    std::string file = "II*" + std::string(1, '\0') + le32(0); // IFD offset patched below
    const size_t strip_bytes = static_cast<size_t>(w) * spp * rps;
    std::vector<uint32_t> offsets, counts;
    for (size_t at = 0; at < px.size(); at += strip_bytes) {
        const std::string z = zlib_stored(px.substr(at, strip_bytes));
        offsets.push_back(static_cast<uint32_t>(file.size()));
        counts.push_back(static_cast<uint32_t>(z.size()));
        file += z;
    }
    // Out-of-line arrays: returns the offset of what it appends.
    auto append = [&](const std::string& bytes) {
        if (file.size() % 2)
            file += '\0';
        const uint32_t at = static_cast<uint32_t>(file.size());
        file += bytes;
        return at;
    };
    std::string bps, extra, offs, cnts;
    for (int c = 0; c < spp; ++c)
        bps += le16(8);
    for (int c = 1; c < spp; ++c)
        extra += le16(0); // unspecified
    for (size_t i = 0; i < offsets.size(); ++i)
        offs += le32(offsets[i]), cnts += le32(counts[i]);
    struct Entry {
        uint16_t tag, type;
        uint32_t count;
        std::string value; // inline when at most 4 bytes
    };
    const uint16_t SHORT = 3, LONG = 4;
    std::vector<Entry> entries = {
        {256, LONG, 1, le32(w)},
        {257, LONG, 1, le32(h)},
        {258, SHORT, uint32_t(spp), bps},
        {259, SHORT, 1, le16(8)},
        {262, SHORT, 1, le16(0)},
        {273, LONG, uint32_t(offsets.size()), offs},
        {277, SHORT, 1, le16(spp)},
        {278, LONG, 1, le32(rps)},
        {279, LONG, uint32_t(counts.size()), cnts},
        {284, SHORT, 1, le16(1)},
        {338, SHORT, uint32_t(spp - 1), extra},
    };
    for (Entry& e : entries)
        e.value = e.value.size() <= 4 ? e.value + std::string(4 - e.value.size(), '\0')
                                      : le32(append(e.value));
    const uint32_t ifd = append(le16(static_cast<uint32_t>(entries.size())));
    for (const Entry& e : entries)
        file += le16(e.tag) + le16(e.type) + le32(e.count) + e.value;
    file += le32(0); // no next IFD
    file.replace(4, 4, le32(ifd));
    return file;
}

} // namespace

TEST(SrgbCurve, KnownValues) {
    EXPECT_NEAR(et::srgb_to_linear(0.5f), 0.21404f, 1e-4f);
    EXPECT_NEAR(et::linear_to_srgb(0.21404f), 0.5f, 1e-4f);
    EXPECT_NEAR(et::linear_to_srgb(0.18f), 0.46135f, 1e-4f);
    EXPECT_FLOAT_EQ(et::srgb_to_linear(0.0f), 0.0f);
    EXPECT_NEAR(et::srgb_to_linear(1.0f), 1.0f, 1e-6f);
    EXPECT_NEAR(et::linear_to_srgb(1.0f), 1.0f, 1e-6f);
    // The linear segment below the breakpoint.
    EXPECT_NEAR(et::srgb_to_linear(0.02f), 0.02f / 12.92f, 1e-8f);
    EXPECT_NEAR(et::linear_to_srgb(0.001f), 0.01292f, 1e-7f);
}

TEST(SrgbCurve, InverseOfEachOtherAndMonotone) {
    float prev_lin = -1.0f, prev_srgb = -1.0f;
    for (int i = 0; i <= 4096; ++i) {
        const float s = i / 4096.0f;
        const float lin = et::srgb_to_linear(s);
        EXPECT_NEAR(et::linear_to_srgb(lin), s, 2e-6f) << "s = " << s;
        EXPECT_NEAR(et::srgb_to_linear(et::linear_to_srgb(s)), s, 2e-6f) << "lin = " << s;
        EXPECT_GT(lin, prev_lin) << s;
        EXPECT_GT(et::linear_to_srgb(s), prev_srgb) << s;
        prev_lin = lin;
        prev_srgb = et::linear_to_srgb(s);
    }
    // Continuous at the breakpoints (the segments meet within float rounding).
    EXPECT_NEAR(et::srgb_to_linear(0.04045f), et::srgb_to_linear(0.04046f), 1e-6f);
    EXPECT_NEAR(et::linear_to_srgb(0.0031308f), et::linear_to_srgb(0.0031309f), 1e-5f);
}

TEST(SrgbCurve, DisplayEncodingClamps) {
    EXPECT_EQ(et::linear_to_srgb(-1.0f), 0.0f);
    EXPECT_EQ(et::linear_to_srgb(5.0f), 1.0f);
    EXPECT_EQ(et::linear_to_srgb(std::nanf("")), 0.0f);
    EXPECT_EQ(et::linear_to_srgb(INFINITY), 1.0f);
}

TEST(ImageIo, FloatExtensions) {
    EXPECT_TRUE(et::is_float_image_extension("a/b.exr"));
    EXPECT_TRUE(et::is_float_image_extension("B.HDR"));
    EXPECT_TRUE(et::is_float_image_extension("c.Pfm"));
    EXPECT_FALSE(et::is_float_image_extension("d.png"));
    EXPECT_FALSE(et::is_float_image_extension("e.jpg"));
    EXPECT_FALSE(et::is_float_image_extension("exr"));
}

TEST(ImageIo, ExrRoundTripIsExact) {
    const std::string dir = ett::scratch_dir("image-io-exr");
    const int w = 37, h = 23; // odd sizes: no row padding hides a stride bug
    const auto px = hdr_pixels(w, h, 3, 1);
    const std::string path = dir + "/round.exr";
    et::write_image(path, w, h, 3, px);
    const et::RgbImage img = et::read_rgb_image(path);
    ASSERT_EQ(img.width, w);
    ASSERT_EQ(img.height, h);
    ASSERT_EQ(img.rgb.size(), px.size());
    for (size_t i = 0; i < px.size(); ++i)
        ASSERT_EQ(img.rgb[i], px[i]) << "index " << i;
    // Row 0 is the top: a pixel read through at() is the one written at that (x, y).
    EXPECT_EQ(img.at(5, 17)[1], px[3 * (17 * w + 5) + 1]);
}

// Radiance RGBE keeps 8 bits per component under the pixel's shared exponent: written and read
// back, every component is within half a step (2^(e-9), m = f 2^e the pixel's largest; twice
// that where m rounds up to 2^e) of what was written, and the errors average out. Written by
// truncation, as the encoders do, they were never above it and 0.28% below on average.
TEST(ImageIo, HdrRoundTripRoundsToNearest) {
    const std::string dir = ett::scratch_dir("image-io-hdr");
    const int w = 64, h = 32;
    const auto px = hdr_pixels(w, h, 3, 5);
    et::write_image(dir + "/r.hdr", w, h, 3, px);
    const et::RgbImage img = et::read_rgb_image(dir + "/r.hdr");
    ASSERT_EQ(img.rgb.size(), px.size());
    double bias = 0.0;
    for (size_t p = 0; p < px.size(); p += 3) {
        const float m = std::max({px[p], px[p + 1], px[p + 2]});
        int e = 0;
        std::frexp(m, &e);
        float half = std::ldexp(1.0f, e - 9);
        if (m + half >= std::ldexp(1.0f, e)) // rounded up into the next exponent
            half *= 2.0f;
        for (int c = 0; c < 3; ++c) {
            ASSERT_LE(std::fabs(img.rgb[p + c] - px[p + c]), half * 1.0001f) << p + c;
            bias += (img.rgb[p + c] - px[p + c]) / half;
        }
    }
    // In units of half a step: truncation gives about -1; rounding about 0 (uniform errors,
    // standard error of the mean sqrt(1/3 / 6144) = 0.007).
    EXPECT_LT(std::fabs(bias / px.size()), 0.05) << bias / px.size();
}

// A PFM written by hand -- `header`, then little-endian floats, bottom row first -- reads as
// the pixels written.
static void expect_hand_written_pfm_reads(const std::string& path, const std::string& header, int w,
                                          int h, uint32_t seed) {
    const auto px = hdr_pixels(w, h, 3, seed);
    {
        std::ofstream out(path, std::ios::binary);
        out << header;
        for (int y = h - 1; y >= 0; --y)
            out.write(reinterpret_cast<const char*>(&px[3 * static_cast<size_t>(y) * w]),
                      3 * w * sizeof(float));
    }
    const et::RgbImage img = et::read_rgb_image(path);
    ASSERT_EQ(img.width, w);
    ASSERT_EQ(img.height, h);
    for (size_t i = 0; i < px.size(); ++i)
        ASSERT_EQ(img.rgb[i], px[i]) << "index " << i;
}

TEST(ImageIo, PfmReadsBottomUpFloatsExactly) {
    expect_hand_written_pfm_reads(ett::scratch_dir("image-io-pfm-read") + "/hand.pfm",
                                  "PF\n5 3\n-1.0\n", 5, 3, 2);
}

// A header written with Windows line ends: the pixels start after the last '\n' (read one
// byte early, every texel was a denormal and the map came out black).
TEST(ImageIo, PfmWithCrLfHeaderReadsTheSamePixels) {
    expect_hand_written_pfm_reads(ett::scratch_dir("image-io-pfm-crlf") + "/crlf.pfm",
                                  "PF\r\n5 3\r\n-1.0\r\n", 5, 3, 7);
}

// Pixels not stored as shown -- a Radiance file stored bottom-up ("+Y H +X W"), an EXR whose data
// window is part of its display window -- are refused with the command that writes them upright,
// not lit upside down or stretched over the sphere.
TEST(ImageIo, TurnedOrCroppedPicturesAreRefused) {
    const std::string dir = ett::scratch_dir("image-io-orientation");
    {
        // Flat RGBE: value 1 is mantissa 128, exponent 129.
        std::ofstream out(dir + "/up.hdr", std::ios::binary);
        out << "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n+Y 2 +X 4\n";
        for (int i = 0; i < 8; ++i)
            out << char(128) << char(128) << char(128) << char(129);
    }
    auto error_of = [](const std::string& path) {
        return ett::error_of([&] { et::read_rgb_image(path); });
    };
    std::string e = error_of(dir + "/up.hdr");
    EXPECT_NE(e.find("up.hdr: its pixels need flipping vertically (stored bottom-up) to be "
                     "upright (orientation 4)"),
              std::string::npos)
        << e;
    EXPECT_NE(e.find("--reorient"), std::string::npos) << e;

    // White pixels written through OpenImageIO with the windows of `spec` (its format: float).
    auto write_white = [](const std::string& path, OIIO::ImageSpec spec) {
        auto out = OIIO::ImageOutput::create(path);
        ASSERT_TRUE(out);
        ASSERT_TRUE(out->open(path, spec)) << out->geterror();
        const std::vector<float> px(size_t(spec.width) * spec.height * spec.nchannels, 1.0f);
        ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, px.data())) << out->geterror();
        out->close();
    };
    OIIO::ImageSpec spec(8, 4, 3, OIIO::TypeDesc::FLOAT);
    spec.full_width = 16;
    spec.full_height = 8;
    write_white(dir + "/crop.exr", spec);
    e = error_of(dir + "/crop.exr");
    EXPECT_NE(e.find("crop.exr: its pixels (data window 8x4+0+0) are not its picture (display "
                     "window 16x8+0+0)"),
              std::string::npos)
        << e;

    // A PNG placed on a page by an oFFs offset (ImageMagick's -crop without +repage) is its
    // picture: OpenImageIO reports the offset as a data window, but only an EXR has two windows.
    OIIO::ImageSpec ps(4, 2, 3, OIIO::TypeDesc::UINT8);
    ps.x = 3;
    ps.y = 2;
    write_white(dir + "/offset.png", ps);
    auto in = OIIO::ImageInput::open(dir + "/offset.png");
    ASSERT_TRUE(in);
    EXPECT_EQ(in->spec().x, 3) << "the test needs a PNG with an offset";
    in.reset();
    const et::RgbImage img = et::read_rgb_image(dir + "/offset.png");
    EXPECT_EQ(img.width, 4);
    EXPECT_EQ(img.height, 2);
    EXPECT_EQ(img.rgb, std::vector<float>(4 * 2 * 3, 1.0f));
}

// A Radiance file of CIE XYZ pixels: refused naming its format (OpenImageIO says it has none).
TEST(ImageIo, RadianceXyzeIsRefusedByName) {
    const std::string path = ett::scratch_dir("image-io-xyze") + "/xyz.hdr";
    std::ofstream(path, std::ios::binary) << "#?RADIANCE\nFORMAT=32-bit_rle_xyze\n\n-Y 1 +X 2\n"
                                          << std::string(8, char(128));
    std::string e;
    try {
        et::read_rgb_image(path);
    } catch (const et::Error& x) {
        e = x.what();
    }
    EXPECT_NE(e.find("xyz.hdr: Radiance XYZE pixels (CIE XYZ) are not read"), std::string::npos)
        << e;
}

// A PNM's maxval of 0 read as "full scale": a black file lit the scene as a white furnace.
// A truncated one says what may be wrong instead of "unknown error".
TEST(ImageIo, PnmMaxvalAndTruncationAreSaid) {
    if (!et::have_image_library())
        GTEST_SKIP() << "no image library in this build";
    const std::string dir = ett::scratch_dir("image-io-pnm");
    std::ofstream(dir + "/zero.ppm", std::ios::binary) << "P6\n# a comment\n4 2\n0\n"
                                                       << std::string(4 * 2 * 3, '\0');
    std::ofstream(dir + "/short.ppm", std::ios::binary) << "P6\n4 2\n255\n" << std::string(5, '\0');
    std::ofstream(dir + "/fine.pgm", std::ios::binary) << "P5 4 2 65535\n"
                                                       << std::string(16, '\x7f');
    EXPECT_NE(ett::error_of([&] {
                  et::read_rgb_image(dir + "/zero.ppm");
              }).find("zero.ppm: PNM header: maxval 0 is not in 1..65535"),
              std::string::npos);
    EXPECT_NE(ett::error_of([&] {
                  et::read_rgb_image(dir + "/short.ppm");
              }).find("the file may be truncated or damaged"),
              std::string::npos);
    EXPECT_EQ(et::read_rgb_image(dir + "/fine.pgm").width, 4);
}

// Radiance's EXPOSURE= says the stored pixels were multiplied by it: read as stored (as
// OpenImageIO and Blender read them), and said, since the map's radiance is off by that factor.
TEST(ImageIo, RadianceExposureIsSaid) {
    const std::string dir = ett::scratch_dir("image-io-exposure");
    for (const char* exposure : {"", "EXPOSURE=2.0\nEXPOSURE=1.5\n", "EXPOSURE=1\n"}) {
        const std::string path = dir + "/e.hdr";
        std::ofstream(path, std::ios::binary) << "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n"
                                              << exposure << "\n-Y 1 +X 2\n"
                                              << std::string(8, char(128));
        ett::WarningCapture warnings;
        EXPECT_EQ(et::read_rgb_image(path).rgb[0], 0.5f); // 128 x 2^(128 - 136): as stored
        EXPECT_EQ(warnings.count_containing("e.hdr: the header's EXPOSURE (3) is not applied"),
                  std::string(exposure).find("2.0") != std::string::npos ? 1u : 0u)
            << exposure;
    }
}

TEST(ImageIo, PfmRoundTripIsExact) {
    const std::string dir = ett::scratch_dir("image-io-pfm");
    const int w = 19, h = 11;
    const auto px = hdr_pixels(w, h, 3, 2);
    const std::string path = dir + "/round.pfm";
    try {
        et::write_image(path, w, h, 3, px);
    } catch (const et::Error& e) {
        if (std::string(e.what()).find("could not find a format writer") != std::string::npos) {
            GTEST_SKIP() << "BUG: image_io.h promises .pfm output (and is_float_image_extension "
                            "accepts it) but OpenImageIO "
                         << OIIO_VERSION_STRING
                         << " has no PFM writer, so write_image(*.pfm) always throws: " << e.what();
        }
        throw;
    }
    const et::RgbImage img = et::read_rgb_image(path);
    ASSERT_EQ(img.width, w);
    ASSERT_EQ(img.height, h);
    for (size_t i = 0; i < px.size(); ++i)
        ASSERT_EQ(img.rgb[i], px[i]) << "index " << i;
    EXPECT_EQ(files_in(dir), std::vector<std::string>{"round.pfm"});
}

TEST(ImageIo, PngDecodesSrgbToLinear) {
    const std::string dir = ett::scratch_dir("image-io-png");
    // Every 8-bit code once per channel, as display values.
    const int w = 256, h = 1;
    std::vector<float> px(3 * w);
    for (int x = 0; x < w; ++x) {
        px[3 * x] = x / 255.0f;
        px[3 * x + 1] = (255 - x) / 255.0f;
        px[3 * x + 2] = 0.5f;
    }
    const std::string path = dir + "/ramp.png";
    et::write_image(path, w, h, 3, px);
    const et::RgbImage img = et::read_rgb_image(path);
    ASSERT_EQ(img.width, w);
    ASSERT_EQ(img.height, h);
    for (int x = 0; x < w; ++x) {
        EXPECT_NEAR(img.at(x, 0)[0], et::srgb_to_linear(x / 255.0f), 1e-5f) << x;
        EXPECT_NEAR(img.at(x, 0)[1], et::srgb_to_linear((255 - x) / 255.0f), 1e-5f) << x;
        // 0.5 is stored as code 128 (or 127): linear ~0.214, not 0.5.
        EXPECT_NEAR(img.at(x, 0)[2], 0.2140f, 0.003f) << x;
    }
}

TEST(ImageIo, OneChannelIsReplicatedToRgb) {
    const std::string dir = ett::scratch_dir("image-io-grey");
    const int w = 8, h = 5;
    const auto grey = hdr_pixels(w, h, 1, 4);
    et::write_image(dir + "/grey.exr", w, h, 1, grey);
    const et::RgbImage img = et::read_rgb_image(dir + "/grey.exr");
    ASSERT_EQ(img.rgb.size(), 3 * grey.size());
    for (size_t p = 0; p < grey.size(); ++p)
        for (int c = 0; c < 3; ++c)
            ASSERT_EQ(img.rgb[3 * p + c], grey[p]) << p << "," << c;

    // An 8-bit grey PNG is replicated after sRGB decoding.
    std::vector<float> g8(w * h);
    for (int i = 0; i < w * h; ++i)
        g8[i] = (i * 7 % 256) / 255.0f;
    et::write_image(dir + "/grey.png", w, h, 1, g8);
    const et::RgbImage png = et::read_rgb_image(dir + "/grey.png");
    for (int i = 0; i < w * h; ++i)
        for (int c = 0; c < 3; ++c)
            ASSERT_NEAR(png.rgb[3 * i + c], et::srgb_to_linear(g8[i]), 1e-5f) << i;
}

TEST(ImageIo, RgbaTakesRgb) {
    const std::string dir = ett::scratch_dir("image-io-rgba");
    const int w = 6, h = 4;
    std::vector<float> px(4 * w * h);
    for (int i = 0; i < w * h; ++i) {
        px[4 * i] = 1.0f + i;
        px[4 * i + 1] = 100.0f + i;
        px[4 * i + 2] = 1000.0f + i;
        px[4 * i + 3] = 0.25f; // alpha must not leak into any channel
    }
    et::write_image(dir + "/rgba.exr", w, h, 4, px);
    const et::RgbImage img = et::read_rgb_image(dir + "/rgba.exr");
    ASSERT_EQ(img.rgb.size(), static_cast<size_t>(3 * w * h));
    for (int i = 0; i < w * h; ++i)
        for (int c = 0; c < 3; ++c)
            ASSERT_EQ(img.rgb[3 * i + c], px[4 * i + c]) << i << "," << c;
}

TEST(ImageIo, RgbaPngTakesRgbIgnoringAlpha) {
    // An 8-bit RGBA PNG as PNG stores it (straight alpha), written straight through OIIO.
    const std::string dir = ett::scratch_dir("image-io-rgba-png");
    const std::string path = dir + "/rgba.png";
    const int w = 3, h = 1;
    const std::vector<unsigned char> bytes = {51,  153, 255, 0,   51,  153,
                                              255, 128, 51,  153, 255, 255};
    {
        auto out = OIIO::ImageOutput::create(path);
        ASSERT_TRUE(out);
        OIIO::ImageSpec spec(w, h, 4, OIIO::TypeDesc::UINT8);
        spec.attribute("oiio:UnassociatedAlpha", 1); // the bytes are stored as given
        ASSERT_TRUE(out->open(path, spec) &&
                    out->write_image(OIIO::TypeDesc::UINT8, bytes.data()) && out->close())
            << out->geterror();
    }
    const et::RgbImage img = et::read_rgb_image(path);
    ASSERT_EQ(img.rgb.size(), 9u);
    const float want[3] = {et::srgb_to_linear(51 / 255.0f), et::srgb_to_linear(153 / 255.0f), 1.0f};
    // Alpha 0, 0.5 and 1: the colour is the file's, never multiplied by alpha.
    for (int x = 0; x < w; ++x)
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(img.at(x, 0)[c], want[c], 1e-5f) << x << "," << c;
}

TEST(ImageIo, RgbaTiffTakesRgbAsStored) {
    // TIFF marks its alpha unassociated (ExtraSamples 2) or associated (1); either way the stored
    // R, G, B are the texels, as for PNG and EXR: three pixels of the same colour with alpha 0,
    // 0.5 and 1 read the same.
    const std::string dir = ett::scratch_dir("image-io-rgba-tiff");
    const int w = 3, h = 1;
    const std::vector<float> px = {0.2f, 0.6f, 0.9f, 0.0f, 0.2f, 0.6f,
                                   0.9f, 0.5f, 0.2f, 0.6f, 0.9f, 1.0f};
    for (const OIIO::TypeDesc type : {OIIO::TypeDesc::UINT8, OIIO::TypeDesc::FLOAT})
        for (int unassociated = 0; unassociated < 2; ++unassociated) {
            const std::string path =
                dir + "/rgba-" + type.c_str() + "-" + std::to_string(unassociated) + ".tif";
            auto out = OIIO::ImageOutput::create(path);
            ASSERT_TRUE(out);
            OIIO::ImageSpec spec(w, h, 4, type);
            spec.attribute("oiio:UnassociatedAlpha", unassociated);
            ASSERT_TRUE(out->open(path, spec) &&
                        out->write_image(OIIO::TypeDesc::FLOAT, px.data()) && out->close())
                << out->geterror();
            const et::RgbImage img = et::read_rgb_image(path);
            ASSERT_EQ(img.rgb.size(), 9u);
            for (int x = 0; x < w; ++x)
                for (int c = 0; c < 3; ++c) {
                    EXPECT_EQ(img.at(x, 0)[c], img.at(2, 0)[c]) << path << ": " << x << "," << c;
                    if (type == OIIO::TypeDesc::FLOAT) {
                        EXPECT_EQ(img.at(x, 0)[c], px[c]) << path << ": " << x << "," << c;
                    }
                }
        }
}

TEST(ImageIo, SixteenBitPngDecodesSrgb) {
    const std::string dir = ett::scratch_dir("image-io-png16");
    const std::string path = dir + "/ramp16.png";
    const int w = 64, h = 2;
    std::vector<uint16_t> px(3 * w * h);
    for (size_t i = 0; i < px.size(); ++i)
        px[i] = static_cast<uint16_t>((i * 1031) % 65536);
    {
        auto out = OIIO::ImageOutput::create(path);
        ASSERT_TRUE(out);
        OIIO::ImageSpec spec(w, h, 3, OIIO::TypeDesc::UINT16);
        ASSERT_TRUE(out->open(path, spec) && out->write_image(OIIO::TypeDesc::UINT16, px.data()) &&
                    out->close())
            << out->geterror();
    }
    const et::RgbImage img = et::read_rgb_image(path);
    ASSERT_EQ(img.rgb.size(), px.size());
    for (size_t i = 0; i < px.size(); ++i)
        ASSERT_NEAR(img.rgb[i], et::srgb_to_linear(px[i] / 65535.0f), 1e-5f) << i;
}

TEST(ImageIo, ChannelsChosenByNameElseTheFirstThree) {
    const std::string dir = ett::scratch_dir("image-io-names");
    const int w = 3, h = 2;
    // Named R, G, B in an unusual order with an extra channel first.
    std::vector<float> px;
    for (int i = 0; i < w * h; ++i)
        for (float v : {-7.0f, 3.0f, 2.0f, 1.0f}) // Z, B, G, R
            px.push_back(v * (i + 1));
    write_named_channels(dir + "/named.exr", w, h, {"Z", "B", "G", "R"}, px);
    const et::RgbImage named = et::read_rgb_image(dir + "/named.exr");
    for (int i = 0; i < w * h; ++i) {
        EXPECT_EQ(named.rgb[3 * i], 1.0f * (i + 1)) << i;
        EXPECT_EQ(named.rgb[3 * i + 1], 2.0f * (i + 1)) << i;
        EXPECT_EQ(named.rgb[3 * i + 2], 3.0f * (i + 1)) << i;
    }

    // Not named R, G, B: the first three channels in file order.
    std::vector<float> q;
    for (int i = 0; i < w * h; ++i)
        for (float v : {1.0f, 2.0f, 3.0f, 4.0f})
            q.push_back(v + 10.0f * i);
    write_named_channels(dir + "/plain.exr", w, h, {"a.x", "a.y", "a.z", "a.w"}, q);
    const et::RgbImage plain = et::read_rgb_image(dir + "/plain.exr");
    // EXR stores channels sorted by name: a.w, a.x, a.y, a.z; whatever OIIO reports first is used,
    // so compare against the file's own order.
    auto in = OIIO::ImageInput::open(dir + "/plain.exr");
    ASSERT_TRUE(in);
    std::vector<float> raw(4 * w * h);
    ASSERT_TRUE(in->read_image(0, 0, 0, 4, OIIO::TypeDesc::FLOAT, raw.data()));
    in->close();
    for (int i = 0; i < w * h; ++i)
        for (int c = 0; c < 3; ++c)
            EXPECT_EQ(plain.rgb[3 * i + c], raw[4 * i + c]) << i << "," << c;

    // A layer's colour ("Image.R", as Blender writes): by name, after a layer without colour.
    // In file order (sorted by name) the first three were Image.B, Image.G, Image.R: swapped.
    std::vector<float> layered;
    for (int i = 0; i < w * h; ++i)
        for (float v : {9.0f, 3.0f, 2.0f, 1.0f}) // Depth.Z, Image.B, Image.G, Image.R
            layered.push_back(v * (i + 1));
    write_named_channels(dir + "/layered.exr", w, h, {"Depth.Z", "Image.B", "Image.G", "Image.R"},
                         layered);
    {
        ett::WarningCapture warnings;
        const et::RgbImage img = et::read_rgb_image(dir + "/layered.exr");
        for (int i = 0; i < w * h; ++i)
            for (int c = 0; c < 3; ++c)
                EXPECT_EQ(img.rgb[3 * i + c], float(c + 1) * (i + 1)) << i << "," << c;
        EXPECT_TRUE(warnings.messages().empty()) << warnings.messages()[0];
    }
    // Channels without colour names are read, and said so (a depth pass would light the scene).
    {
        ett::WarningCapture warnings;
        write_named_channels(dir + "/depth.exr", w, h, {"Z"}, std::vector<float>(w * h, 7.0f));
        EXPECT_EQ(et::read_rgb_image(dir + "/depth.exr").rgb[0], 7.0f);
        EXPECT_EQ(warnings.count_containing(
                      "no channels named as colour (R, G, B) or luminance (Y) among Z; read Z as "
                      "grey"),
                  1u);
    }
}

TEST(ImageIo, WriteLeavesNoTemporaryFiles) {
    const std::string dir = ett::scratch_dir("image-io-tmp");
    const auto px = hdr_pixels(4, 4, 3, 5);
    for (const char* name : {"a.exr", "b.hdr", "d.png", "E.EXR"})
        et::write_image(dir + "/" + name, 4, 4, 3, px);
    EXPECT_EQ(files_in(dir), (std::vector<std::string>{"E.EXR", "a.exr", "b.hdr", "d.png"}));
    // An upper-case .EXR is still a float image.
    EXPECT_EQ(et::read_rgb_image(dir + "/E.EXR").rgb, px);
}

TEST(ImageIo, WriteReplacesByRenaming) {
    const std::string dir = ett::scratch_dir("image-io-replace");
    const std::string path = dir + "/out.exr", link = dir + "/old-link.exr";
    const auto first = hdr_pixels(8, 8, 3, 6), second = hdr_pixels(8, 8, 3, 7);
    et::write_image(path, 8, 8, 3, first);
    const std::string first_bytes = read_all(path);
    // A hard link to the first file: a rename replaces the name and leaves the old inode (and so
    // the link) intact, while writing in place would change the link's content too.
    fs::create_hard_link(path, link);
    et::write_image(path, 8, 8, 3, second);
    EXPECT_EQ(read_all(link), first_bytes) << "the old file was rewritten in place";
    EXPECT_EQ(et::read_rgb_image(path).rgb, second);
    EXPECT_EQ(et::read_rgb_image(link).rgb, first);
    EXPECT_EQ(files_in(dir), (std::vector<std::string>{"old-link.exr", "out.exr"}));
}

TEST(ImageIo, FailedWriteLeavesTargetAndNoTemporary) {
    const std::string dir = ett::scratch_dir("image-io-fail");
    const std::string path = dir + "/keep.exr";
    const auto px = hdr_pixels(4, 4, 3, 8);
    et::write_image(path, 4, 4, 3, px);
    const std::string before = read_all(path);

    // Unsupported format: refused by name, nothing created.
    expect_error_naming(dir + "/x.bmp", [&] { et::write_image(dir + "/x.bmp", 4, 4, 3, px); });
    // Missing folder.
    expect_error_naming(dir + "/no/such/dir/x.exr",
                        [&] { et::write_image(dir + "/no/such/dir/x.exr", 4, 4, 3, px); });
    // A folder where the file should go: the rename fails, the temporary must go.
    fs::create_directory(dir + "/taken.exr");
    fs::create_directory(dir + "/taken.exr/inner"); // a non-empty folder cannot be renamed over
    expect_error_naming(dir + "/taken.exr",
                        [&] { et::write_image(dir + "/taken.exr", 4, 4, 3, px); });

    EXPECT_EQ(read_all(path), before);
    EXPECT_EQ(files_in(dir), (std::vector<std::string>{"keep.exr", "taken.exr"}));
}

// A full disk while the 8-bit preview is written: OpenImageIO's PNG writer reported success and
// a truncated preview was committed with exit status 0. /dev/full fails every write (ENOSPC).
TEST(ImageIo, PreviewWriteErrorsAreReported) {
    if (!et::have_image_library())
        GTEST_SKIP() << "no image library in this build";
    const std::string dir = ett::scratch_dir("image-io-full");
    const std::vector<float> px(8 * 8 * 3, 0.5f);
    for (const char* name : {"preview.png", "preview.jpg"}) {
        const std::string full = dir + "/full-" + name; // the temporary's name, on a full disk
        fs::remove(full);
        fs::create_symlink("/dev/full", full);
        const std::string e = ett::error_of([&] {
            et::image_detail::write_with_library(name, full, 8, 8, 3, px.data(), false, {},
                                                 nullptr);
        });
        EXPECT_NE(e.find(std::string(name) + ": cannot write: No space left on device"),
                  std::string::npos)
            << "'" << e << "'";
    }
}

TEST(ImageIo, AttributesAreStored) {
    const std::string dir = ett::scratch_dir("image-io-attr");
    et::write_image(dir + "/a.exr", 2, 2, 3, hdr_pixels(2, 2, 3, 9),
                    {{"envtrace:scene", "cornell_box.json"}, {"envtrace:spp", "64"}});
    auto in = OIIO::ImageInput::open(dir + "/a.exr");
    ASSERT_TRUE(in) << OIIO::geterror();
    EXPECT_EQ(in->spec().get_string_attribute("envtrace:scene"), "cornell_box.json");
    EXPECT_EQ(in->spec().get_string_attribute("envtrace:spp"), "64");
}

TEST(ImageIo, UnreadablePathsThrowNamingTheFile) {
    const std::string dir = ett::scratch_dir("image-io-bad");
    expect_error_naming(dir + "/missing.exr", [&] { et::read_rgb_image(dir + "/missing.exr"); });
    std::ofstream(dir + "/empty.hdr").close();
    expect_error_naming(dir + "/empty.hdr", [&] { et::read_rgb_image(dir + "/empty.hdr"); });
    fs::create_directory(dir + "/folder.exr");
    expect_error_naming(dir + "/folder.exr", [&] { et::read_rgb_image(dir + "/folder.exr"); });
    std::ofstream(dir + "/junk.exr") << "this is not an image\nat all\n";
    expect_error_naming(dir + "/junk.exr", [&] { et::read_rgb_image(dir + "/junk.exr"); });
    // A truncated EXR: a valid header, the pixel data cut off.
    et::write_image(dir + "/whole.exr", 64, 64, 3, hdr_pixels(64, 64, 3, 10));
    const std::string bytes = read_all(dir + "/whole.exr");
    std::ofstream(dir + "/cut.exr", std::ios::binary) << bytes.substr(0, bytes.size() / 3);
    expect_error_naming(dir + "/cut.exr", [&] { et::read_rgb_image(dir + "/cut.exr"); });
}

// RgbImageReader in bands of any size gives exactly what read_rgb_image gives, on every path:
// float RGB decoded in place, half converted, a grey channel replicated, tiles (bands that cut
// through them), a data window that does not start at 0, strips, Radiance HDR and PFM.
TEST(ImageIo, ReaderBandsOfAnySizeGiveTheWholeImage) {
    const std::string dir = ett::scratch_dir("image-io-bands");
    const int w = 37, h = 29;
    const std::vector<float> px = hdr_pixels(w, h, 3, 4);
    et::write_image(dir + "/float.exr", w, h, 3, px);
    et::write_image(dir + "/map.pfm", w, h, 3, px);
    et::write_image(dir + "/map.hdr", w, h, 3, px);
    std::vector<std::string> paths = {dir + "/float.exr", dir + "/map.pfm", dir + "/map.hdr"};
    struct Variant {
        const char* name;
        OIIO::TypeDesc type;
        int channels, tile, y_origin;
    };
    for (const Variant& v : {Variant{"/half-tiled.exr", OIIO::TypeDesc::HALF, 3, 8, 0},
                             Variant{"/window.exr", OIIO::TypeDesc::HALF, 4, 0, 3},
                             Variant{"/grey-strips.tif", OIIO::TypeDesc::FLOAT, 1, 0, 0},
                             Variant{"/rgb16-tiled.tif", OIIO::TypeDesc::UINT16, 3, 16, 0}}) {
        const std::string path = dir + v.name;
        auto out = OIIO::ImageOutput::create(path);
        ASSERT_TRUE(out);
        OIIO::ImageSpec spec(w, h, v.channels, v.type);
        spec.y = spec.full_y = v.y_origin; // the display window where the data is
        if (v.tile)
            spec.tile_width = spec.tile_height = v.tile;
        else
            spec.attribute("tiff:RowsPerStrip", 5);
        std::vector<float> data(static_cast<size_t>(w) * h * v.channels);
        for (size_t p = 0; p < data.size(); ++p)
            data[p] = px[(p / v.channels) * 3 + p % v.channels % 3] / 1e4f;
        ASSERT_TRUE(out->open(path, spec) && out->write_image(OIIO::TypeDesc::FLOAT, data.data()) &&
                    out->close())
            << out->geterror();
        paths.push_back(path);
    }
    for (const std::string& path : paths) {
        const et::RgbImage whole = et::read_rgb_image(path);
        ASSERT_EQ(whole.width, w) << path;
        ASSERT_EQ(whole.height, h) << path;
        for (int band : {1, 5, 8, 13, 64}) {
            et::RgbImageReader reader(path);
            std::vector<float> rgb(whole.rgb.size(), -1.0f);
            int y = 0;
            while (const int n =
                       reader.read_rows(band, rgb.data() + 3 * static_cast<size_t>(y) * w))
                y += n;
            EXPECT_EQ(y, h) << path;
            EXPECT_EQ(rgb, whole.rgb) << path << ", bands of " << band;
        }
    }
}

namespace {

// Radiance files made byte by byte: a header, then scanlines RLE-encoded (runs where three or more
// bytes repeat), flat, or given as raw bytes.
std::string rgbe_header(int w, int h, const std::string& resolution = "") {
    return "#?RADIANCE\n# made by the test\nEXPOSURE=1.0\nFORMAT=32-bit_rle_rgbe\n\n" +
           (resolution.empty() ? "-Y " + std::to_string(h) + " +X " + std::to_string(w)
                               : resolution) +
           "\n";
}

std::string rgbe_rle_scanline(const std::vector<std::array<unsigned char, 4>>& px) {
    const int w = static_cast<int>(px.size());
    std::string out = {2, 2, static_cast<char>(w >> 8), static_cast<char>(w & 255)};
    for (int c = 0; c < 4; ++c)
        for (int x = 0; x < w;) {
            int n = 1;
            while (x + n < w && n < 127 && px[x + n][c] == px[x][c])
                ++n;
            if (n >= 3) {
                out += {static_cast<char>(128 + n), static_cast<char>(px[x][c])};
            } else {
                n = std::min(128, w - x);
                out += static_cast<char>(n);
                for (int i = 0; i < n; ++i)
                    out += static_cast<char>(px[x + i][c]);
            }
            x += n;
        }
    return out;
}

std::string rgbe_flat_scanline(const std::vector<std::array<unsigned char, 4>>& px) {
    std::string out;
    for (const auto& p : px)
        out.append(reinterpret_cast<const char*>(p.data()), 4);
    return out;
}

std::vector<std::array<unsigned char, 4>> rgbe_pixels(int w, std::mt19937& rng) {
    std::vector<std::array<unsigned char, 4>> px(w);
    for (int x = 0; x < w; ++x)
        for (int c = 0; c < 4; ++c)
            px[x][c] = x % 5 == 0 ? 10 : static_cast<unsigned char>(rng()); // runs and noise
    px[0][0] = 3; // a flat scanline must not start with 2, 2
    return px;
}

} // namespace

// Radiance pixels are decoded by envtrace (OpenImageIO reads the header): every file decodes bit
// for bit as OpenImageIO's reader decodes it, or both refuse it. RLE and flat scanlines, mixed,
// narrow and wide (flat) images, bottom-up files (refused: not upright), every exponent
// (OpenImageIO's table has three entries that are not powers of two), and broken runs, widths and
// ends.
TEST(ImageIo, RadianceDecodedBitForBitAsOpenImageIo) {
    const std::string dir = ett::scratch_dir("image-io-rgbe");
    std::mt19937 rng(3);
    std::vector<std::pair<std::string, std::string>> files;
    const int w = 40, h = 6;
    std::string rle = rgbe_header(w, h), mixed = rle, bottom_up = rgbe_header(w, h, "+Y 6 +X 40");
    for (int y = 0; y < h; ++y) {
        const auto px = rgbe_pixels(w, rng);
        rle += rgbe_rle_scanline(px);
        bottom_up += rgbe_rle_scanline(px);
        mixed += y % 2 ? rgbe_flat_scanline(px) : rgbe_rle_scanline(px);
    }
    files.push_back({"rle", rle});
    files.push_back({"mixed", mixed});
    files.push_back({"bottom-up", bottom_up});
    std::vector<std::array<unsigned char, 4>> exponents(256);
    for (int e = 0; e < 256; ++e)
        exponents[e] = {static_cast<unsigned char>(255 - e), 1, 128, static_cast<unsigned char>(e)};
    files.push_back({"exponents", rgbe_header(256, 1) + rgbe_rle_scanline(exponents)});
    files.push_back({"narrow", rgbe_header(5, 2) + rgbe_flat_scanline(rgbe_pixels(10, rng))});
    files.push_back({"wide", rgbe_header(40000, 1) + rgbe_flat_scanline(rgbe_pixels(40000, rng))});
    files.push_back({"truncated", rle.substr(0, rle.size() - 30)});
    std::string broken = rle;
    const size_t data = rgbe_header(w, h).size();
    broken[data + 3] = 41; // scanline width
    files.push_back({"width", broken});
    broken = rle;
    broken[data + 4] = 0; // a run of 0
    files.push_back({"run0", broken});
    broken[data + 4] = static_cast<char>(128 + 100); // a run past the end of the scanline
    files.push_back({"overrun", broken});
    for (int i = 0; i < 200; ++i) { // and random damage
        std::string f = i % 2 ? mixed : rle;
        for (int k = 0; k < 3; ++k)
            f[data + rng() % (f.size() - data)] = static_cast<char>(rng());
        files.push_back({"damaged" + std::to_string(i), f});
    }
    for (const auto& [name, bytes] : files) {
        const std::string path = dir + "/" + name + ".hdr";
        std::ofstream(path, std::ios::binary) << bytes;
        std::vector<float> want;
        bool oiio_ok = false;
        if (auto in = OIIO::ImageInput::open(path)) {
            want.resize(3 * static_cast<size_t>(in->spec().width) * in->spec().height);
            oiio_ok = in->read_image(0, 0, 0, 3, OIIO::TypeDesc::FLOAT, want.data());
        }
        (void)OIIO::geterror();
        try {
            const et::RgbImage img = et::read_rgb_image(path);
            EXPECT_TRUE(oiio_ok) << name << ": OpenImageIO refuses it, envtrace reads it";
            EXPECT_EQ(img.rgb.size(), want.size()) << name;
            EXPECT_EQ(std::memcmp(img.rgb.data(), want.data(),
                                  std::min(img.rgb.size(), want.size()) * sizeof(float)),
                      0)
                << name;
        } catch (const et::Error& e) {
            // OpenImageIO reads a bottom-up file's rows as stored (and says so in its
            // Orientation); envtrace refuses to light a scene upside down.
            if (name == "bottom-up") {
                EXPECT_NE(std::string(e.what()).find("flipping vertically"), std::string::npos)
                    << e.what();
                continue;
            }
            EXPECT_FALSE(oiio_ok) << name << ": OpenImageIO reads it, envtrace says " << e.what();
            EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
        }
    }
}

// Fuzz finding F8: OpenImageIO 2.4 decodes a range of whole zip strips of a TIFF itself and, for
// MinIsWhite, inverts nchannels times too many values per strip, far past its buffer (a 191-byte
// TIFF crashed the CLI). Such files are read a scanline at a time, which libtiff inverts right:
// a 64-channel MinIsWhite TIFF in 4 zip strips reads as its inverted R, G, B (sRGB decoded).
TEST(ImageIo, MinIsWhiteTiffOfManyChannelsReadsInvertedWithoutOverrun) {
    const std::string path = ett::scratch_dir("image-io-miniswhite") + "/mw.tif";
    const int w = 128, h = 64, spp = 64, rps = 16;
    std::string px(static_cast<size_t>(w) * h * spp, '\x55');
    auto stored = [](int x, int y, int c) {
        return static_cast<unsigned char>(x * 3 + y * 5 + c * 7);
    };
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c)
                px[(static_cast<size_t>(y) * w + x) * spp + c] = static_cast<char>(stored(x, y, c));
    {
        std::ofstream f(path, std::ios::binary);
        f << miniswhite_tiff(w, h, spp, rps, px);
    }
    const et::RgbImage img = et::read_rgb_image(path);
    ASSERT_EQ(img.width, w);
    ASSERT_EQ(img.height, h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c)
                ASSERT_NEAR(img.at(x, y)[c], et::srgb_to_linear((255 - stored(x, y, c)) / 255.0f),
                            1e-6f)
                    << x << "," << y << "," << c;
}

// F8 again (F8b): the heap corruption of a later long run in a build without F8's workaround was
// the same overrun, and it is not only a matter of 64-channel oddities: a 4-channel (grey + 3
// extra samples) MinIsWhite zip TIFF already writes past the strip buffer (ASan: bad-free in
// OpenImageIO 2.4), a 2-channel one too, and strips that fail to decode are inverted all the
// same. Every such file reads inverted, a scanline at a time; one whose strips are not valid
// deflate is one et::Error naming the file, not a crash.
TEST(ImageIo, MinIsWhiteTiffsOfFewChannelsAndBrokenStripsReadWithoutOverrun) {
    const std::string dir = ett::scratch_dir("image-io-miniswhite-few");
    auto stored = [](int x, int y, int c) {
        return static_cast<unsigned char>(x * 5 + y * 3 + c * 11);
    };
    for (int spp : {2, 3, 4}) {
        const int w = 64, h = 48, rps = 8;
        std::string px(static_cast<size_t>(w) * h * spp, '\0');
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                for (int c = 0; c < spp; ++c)
                    px[(static_cast<size_t>(y) * w + x) * spp + c] =
                        static_cast<char>(stored(x, y, c));
        const std::string path = dir + "/mw" + std::to_string(spp) + ".tif";
        std::ofstream(path, std::ios::binary) << miniswhite_tiff(w, h, spp, rps, px);
        const et::RgbImage img = et::read_rgb_image(path);
        ASSERT_EQ(img.width, w) << spp;
        ASSERT_EQ(img.height, h) << spp;
        // Three or more channels: the first three; two (grey + one extra): grey replicated.
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                for (int c = 0; c < 3; ++c) {
                    const int from = spp >= 3 ? c : 0;
                    ASSERT_NEAR(img.at(x, y)[c],
                                et::srgb_to_linear((255 - stored(x, y, from)) / 255.0f), 1e-6f)
                        << spp << " channels: " << x << "," << y << "," << c;
                }

        // The same file with each strip's zlib header spoilt (the strips lie one after the
        // other from offset 8, all of one size): every strip fails to decode.
        std::string broken = miniswhite_tiff(w, h, spp, rps, px);
        const size_t strip_z = zlib_stored(px.substr(0, static_cast<size_t>(w) * spp * rps)).size();
        for (int s = 0; s < h / rps; ++s) {
            const size_t at = 8 + s * strip_z;
            ASSERT_EQ(broken.substr(at, 2), "\x78\x01");
            broken[at] = '\xff', broken[at + 1] = '\xff';
        }
        const std::string bad = dir + "/broken" + std::to_string(spp) + ".tif";
        std::ofstream(bad, std::ios::binary) << broken;
        expect_error_naming(bad, [&] { et::read_rgb_image(bad); });
    }
}

// Fuzz finding F9: a PFM whose header was refused left its file open (the constructor threw past
// the destructor that closed it); 20000 descriptors ran out after 89162 fuzz executions. Every
// refused file, whatever its format and wherever it is refused, leaves no descriptor open.
TEST(ImageIo, RefusedFilesLeaveNoFileOpen) {
    const std::string dir = ett::scratch_dir("image-io-fd");
    auto open_fds = [] {
        int n = 0;
        for (const auto& e : fs::directory_iterator("/proc/self/fd")) {
            (void)e;
            ++n;
        }
        return n;
    };
    const std::vector<std::pair<std::string, std::string>> files = {
        {"header.pfm", "PF\nfour 2\n-1.0\n" + std::string(96, '\0')},
        {"magic.pfm", "P6\n4 2\n255\n" + std::string(24, '\0')},
        {"scale.pfm", "PF\n4 2\n0\n" + std::string(96, '\0')},
        {"short.pfm", "PF\n4 2\n-1.0\n" + std::string(10, '\0')},
        {"huge.pfm", "PF\n30000 15000\n-1.0\n" + std::string(64, '\0')},
        {"cut.hdr", "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 8 +X 16\n\2\2\0\20"},
        {"garbage.exr", "v/1\1" + std::string(60, 'x')},
        {"cut.png", "\x89PNG\r\n\x1a\n" + std::string(40, '\0')},
    };
    for (const auto& [name, bytes] : files) {
        // A copy: clang before C++20 does not let a lambda capture a structured binding.
        const std::string path = dir + "/" + name;
        std::ofstream(path, std::ios::binary) << bytes;
        expect_error_naming(path, [&] { et::read_rgb_image(path); });
    }
    const int before = open_fds();
    for (int round = 0; round < 10; ++round)
        for (const auto& [name, bytes] : files) {
            try {
                et::RgbImageReader reader(dir + "/" + name);
                std::vector<float> rows(static_cast<size_t>(reader.width()) * 3 *
                                        reader.band_rows());
                reader.read_rows(reader.band_rows(), rows.data());
            } catch (const et::Error&) {
            }
        }
    EXPECT_EQ(open_fds(), before);
}

// Fuzz finding F10: OpenEXR allocates what a header attribute's size field claims before reading
// it (456 bytes claiming a 1.7 GB string took 1.8 GB). The header is checked here first: sizes
// beyond the file and previews larger than their attribute are refused by name, whatever the
// file is called; valid headers (every other EXR test) still load.
TEST(ImageIo, ExrAttributeSizesBeyondTheFileAreRefusedBeforeOpenExrAllocates) {
    const std::string dir = ett::scratch_dir("image-io-exr-header");
    auto le32 = [](uint32_t v) {
        return std::string{char(v), char(v >> 8), char(v >> 16), char(v >> 24)};
    };
    const std::string magic = std::string("\x76\x2f\x31\x01", 4) + std::string("\x02\0\0\0", 4);
    const std::string huge_string =
        magic + std::string("comments\0string\0", 16) + le32(1700000000) + "abc";
    const std::string big_preview = magic + std::string("preview\0preview\0", 16) + le32(16) +
                                    le32(4000) + le32(4000) + std::string(8, '\0');
    const std::string negative = magic + std::string("owner\0string\0", 13) + le32(0xfffffff0u);
    const std::vector<std::pair<std::string, std::string>> files = {
        {"huge-string.exr", huge_string},
        {"huge-string.png", huge_string},
        {"big-preview.exr", big_preview},
        {"negative.exr", negative}};
    for (const auto& [name, bytes] : files) {
        const std::string path = dir + "/" + name;
        std::ofstream(path, std::ios::binary) << bytes;
        try {
            et::read_rgb_image(path);
            ADD_FAILURE() << path << ": read";
        } catch (const et::Error& e) {
            const std::string m = e.what();
            EXPECT_EQ(m.rfind(path, 0), 0u) << m;
            EXPECT_NE(m.find("corrupt EXR header"), std::string::npos) << m;
        }
    }
}

namespace {

std::string le32(uint32_t v) {
    return std::string{char(v), char(v >> 8), char(v >> 16), char(v >> 24)};
}

// One header attribute: name, type, size (the value's length unless given) and value.
std::string exr_attr(const std::string& name, const std::string& type, const std::string& value,
                     int64_t size = -1) {
    return name + '\0' + type + '\0' +
           le32(static_cast<uint32_t>(size < 0 ? int64_t(value.size()) : size)) + value;
}

std::string exr_box(int x0, int y0, int x1, int y1) {
    return le32(x0) + le32(y0) + le32(x1) + le32(y1);
}

// A channel list of FLOAT (or `type`) channels sampled 1x1.
std::string exr_chlist(const std::vector<std::string>& names, int type = 2) {
    std::string v;
    for (const std::string& n : names)
        v += n + '\0' + le32(type) + std::string(4, '\0') + le32(1) + le32(1);
    return v + '\0';
}

// A hand-written single-part scanline EXR of 4x2 float B, G, R pixels, uncompressed: magic,
// version field (2 | flags), `attrs` (the required ones by default, in the order OpenEXR writes
// them), the end of the header, the offset table and two chunks. Pixel (x, y) is
// (1 + x, 10 + y, 0.5). The attribute list is a vector so that tests can damage one entry.
struct HandExr {
    uint32_t flags = 0;
    std::vector<std::string> attrs = {
        exr_attr("channels", "chlist", exr_chlist({"B", "G", "R"})),
        exr_attr("compression", "compression", std::string(1, '\0')),
        exr_attr("dataWindow", "box2i", exr_box(0, 0, 3, 1)),
        exr_attr("displayWindow", "box2i", exr_box(0, 0, 3, 1)),
        exr_attr("lineOrder", "lineOrder", std::string(1, '\0')),
        exr_attr("pixelAspectRatio", "float", le32(0x3f800000)),
        exr_attr("screenWindowCenter", "v2f", std::string(8, '\0')),
        exr_attr("screenWindowWidth", "float", le32(0x3f800000)),
    };
    std::string bytes() const {
        std::string head = std::string("\x76\x2f\x31\x01", 4) + le32(2 | flags);
        for (const std::string& a : attrs)
            head += a;
        head += '\0';
        if (flags & 0x1000)
            head += '\0'; // the empty header that ends a multi-part file's headers
        std::string chunks[2];
        for (int y = 0; y < 2; ++y) {
            std::string data;
            for (float v : {0.5f, 10.0f + y}) // B, then G: planar per channel, x fastest
                for (int x = 0; x < 4; ++x) {
                    uint32_t u;
                    std::memcpy(&u, &v, 4);
                    data += le32(u);
                }
            for (int x = 0; x < 4; ++x) {
                const float v = 1.0f + x; // R
                uint32_t u;
                std::memcpy(&u, &v, 4);
                data += le32(u);
            }
            chunks[y] = le32(y) + le32(static_cast<uint32_t>(data.size())) + data;
        }
        const uint64_t first = head.size() + 16;
        auto le64 = [](uint64_t v) { return le32(uint32_t(v)) + le32(uint32_t(v >> 32)); };
        return head + le64(first) + le64(first + chunks[0].size()) + chunks[0] + chunks[1];
    }
};

// Peak resident memory of this process so far, in MB.
double peak_rss_mb() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return u.ru_maxrss / 1024.0;
}

} // namespace

// Fuzz finding F11 and its class: OpenEXR reads a value of a type it knows by its content, not by
// its size field, and reads the next attribute where that content ended. A channel list whose
// size field claims more than its entries (F11: 527 bytes) hid, inside the bytes F10's walk
// skipped, a string that OpenEXR then allocated (1 GB; 1.2 GB peak, 2.4 s). Every header is now
// parsed as OpenEXR parses it, and each way a header can claim what its file cannot hold, or
// lack what the reader needs, is one et::Error naming the file and the problem, before OpenEXR
// allocates anything. The valid hand-written file beside them loads, so each broken variant is
// refused for its own damage.
TEST(ImageIo, ExrHeadersThatCannotBeRightAreRefusedBeforeOpenExrReadsThem) {
    const std::string dir = ett::scratch_dir("image-io-exr-walk");
    const HandExr good;
    {
        const std::string path = dir + "/good.exr";
        std::ofstream(path, std::ios::binary) << good.bytes();
        const et::RgbImage img = et::read_rgb_image(path);
        ASSERT_EQ(img.width, 4);
        ASSERT_EQ(img.height, 2);
        for (int y = 0; y < 2; ++y)
            for (int x = 0; x < 4; ++x) {
                EXPECT_EQ(img.at(x, y)[0], 1.0f + x);
                EXPECT_EQ(img.at(x, y)[1], 10.0f + y);
                EXPECT_EQ(img.at(x, y)[2], 0.5f);
            }
    }
    struct Case {
        const char* name;
        HandExr exr;
        const char* expect; // in the message
    };
    std::vector<Case> cases;
    auto variant = [&](const char* name, const char* expect, auto&& damage) {
        HandExr e;
        damage(e);
        cases.push_back({name, e, expect});
    };
    // F11's shape: the channel list's size covers a string attribute claiming 1.09 GB (the
    // file's own 0x41000004), which OpenEXR reads as the next attribute.
    variant("f11-hidden-string", "channels take", [](HandExr& e) {
        const std::string hidden = exr_attr("comments", "string", "", 0x41000004);
        const std::string list = exr_chlist({"B", "G", "R"});
        e.attrs[0] = exr_attr("channels", "chlist", list + hidden, list.size() + hidden.size());
    });
    variant("chlist-short", "channels take", [](HandExr& e) {
        e.attrs[0] = exr_attr("channels", "chlist", exr_chlist({"B", "G", "R"}), 20);
    });
    variant("chlist-type", "pixel type 7", [](HandExr& e) {
        e.attrs[0] = exr_attr("channels", "chlist", exr_chlist({"B", "G", "R"}, 7));
    });
    variant("chlist-twice", "appears twice in the channel list", [](HandExr& e) {
        e.attrs[0] = exr_attr("channels", "chlist", exr_chlist({"B", "B", "R"}));
    });
    variant("chlist-empty", "channel list is empty",
            [](HandExr& e) { e.attrs[0] = exr_attr("channels", "chlist", exr_chlist({})); });
    variant("box-size", "a box2i has 16 bytes",
            [](HandExr& e) { e.attrs.push_back(exr_attr("crop", "box2i", std::string(8, '\0'))); });
    variant("float-size", "a float has 4 bytes", [](HandExr& e) {
        e.attrs[5] = exr_attr("pixelAspectRatio", "float", std::string(40, '\0'));
    });
    variant("stringvector", "a string claims 1090519044 bytes", [](HandExr& e) {
        e.attrs.push_back(
            exr_attr("multiView", "stringvector", le32(5) + "right" + le32(0x41000004) + "le"));
    });
    variant("huge-string", "claims 1700000000 bytes",
            [](HandExr& e) { e.attrs.push_back(exr_attr("owner", "string", "abc", 1700000000)); });
    variant("no-data-window", "no dataWindow attribute",
            [](HandExr& e) { e.attrs.erase(e.attrs.begin() + 2); });
    variant("no-channels", "no channels attribute",
            [](HandExr& e) { e.attrs.erase(e.attrs.begin()); });
    variant("data-window-type", "expected type box2i",
            [](HandExr& e) { e.attrs[2] = exr_attr("dataWindow", "v2f", std::string(8, '\0')); });
    variant("attribute-twice", "appears twice", [](HandExr& e) { e.attrs.push_back(e.attrs[4]); });
    variant("compression", "unknown compression method 42", [](HandExr& e) {
        e.attrs[1] = exr_attr("compression", "compression", std::string(1, char(42)));
    });
    variant("window-empty", "dataWindow (0, 0) - (-5, 1) is empty",
            [](HandExr& e) { e.attrs[2] = exr_attr("dataWindow", "box2i", exr_box(0, 0, -5, 1)); });
    // 300000000 x 1 float RGB: 3.6 GB of texels, refused by the budget before OpenEXR sees it.
    // PIZ: no ratio bound on what the file holds, so the budget is what refuses it.
    variant("window-budget", "memory budget", [](HandExr& e) {
        e.attrs[1] = exr_attr("compression", "compression", std::string(1, char(4)));
        e.attrs[2] = exr_attr("dataWindow", "box2i", exr_box(0, 0, 299999999, 0));
    });
    // 1 x 50000000 (600 MB of texels, within the budget): 50M offsets of 8 bytes.
    variant("chunk-table", "chunks need at least", [](HandExr& e) {
        e.attrs[2] = exr_attr("dataWindow", "box2i", exr_box(0, 0, 0, 49999999));
    });
    // 30000 x 1 uncompressed (360 kB stored, about 1000:1 of the file): OpenEXR read such a
    // header "successfully" (a mutant of 5439552x32 half took 2 GB and 70 s), filling texels from
    // nowhere; uncompressed pixels must be in the file.
    variant("pixels-beyond-file", "more than uncompressed storage can fit", [](HandExr& e) {
        e.attrs[2] = exr_attr("dataWindow", "box2i", exr_box(0, 0, 29999, 0));
    });
    variant("deep", "deep EXR images are not supported", [](HandExr& e) { e.flags = 0x800; });
    variant("tiled-no-tiles", "no tiles attribute", [](HandExr& e) { e.flags = 0x200; });
    variant("huge-tiles", "larger than the memory budget", [](HandExr& e) {
        e.flags = 0x200;
        e.attrs.push_back(exr_attr("tiles", "tiledesc", le32(65536) + le32(65536) + '\0'));
    });
    // A mutant found by walking: 16x6225936 tiles of a 37x21 image took 1.27 GB.
    variant("tall-tiles", "larger than both the image and 256 MB", [](HandExr& e) {
        e.flags = 0x200;
        e.attrs.push_back(exr_attr("tiles", "tiledesc", le32(16) + le32(6225936) + '\0'));
    });
    variant("flags", "unknown flags", [](HandExr& e) { e.flags = 0x4000; });
    variant("multipart-no-name", "no name, type, chunkCount attribute",
            [](HandExr& e) { e.flags = 0x1000; });
    variant("multipart-chunks", "chunkCount 1000000000", [](HandExr& e) {
        e.flags = 0x1000;
        e.attrs.push_back(exr_attr("name", "string", "rgba"));
        e.attrs.push_back(exr_attr("type", "string", "scanlineimage"));
        e.attrs.push_back(exr_attr("chunkCount", "int", le32(1000000000)));
    });

    const double rss_before = peak_rss_mb();
    for (const Case& c : cases) {
        // Named .png too: the check goes by the magic, not the name.
        for (const char* ext : {".exr", ".png"}) {
            const std::string path = dir + "/" + c.name + ext;
            std::ofstream(path, std::ios::binary) << c.exr.bytes();
            try {
                et::read_rgb_image(path);
                ADD_FAILURE() << path << ": read";
            } catch (const et::Error& e) {
                const std::string m = e.what();
                EXPECT_EQ(m.rfind(path + ": ", 0), 0u) << m;
                EXPECT_NE(m.find(c.expect), std::string::npos) << c.name << ": " << m;
                EXPECT_EQ(m.find('\n'), std::string::npos) << m;
            }
        }
    }
    // Before the walk parsed values, the F11 variant alone took over 1 GB (OpenEXR zero-fills the
    // string it allocates); refused files cost nothing like that now.
    EXPECT_LT(peak_rss_mb() - rss_before, 200.0);
}

// The walk accepts what OpenEXR writes: every compression, half and float, tiles of any size,
// MIP-mapped textures, multi-part files (the first part is read), data windows off the origin,
// decreasing line order, extra channels. Each still reads as written.
TEST(ImageIo, ValidExrLayoutsStillLoadPastTheHeaderWalk) {
    const std::string dir = ett::scratch_dir("image-io-exr-valid");
    const int w = 37, h = 21;
    const std::vector<float> px = hdr_pixels(w, h, 3, 11);
    struct Layout {
        std::string name;
        OIIO::TypeDesc type;
        std::string compression;
        int tile_w = 0, tile_h = 0, x = 0, y = 0;
        bool decreasing = false, multipart = false;
        int channels = 3;
    };
    std::vector<Layout> layouts;
    for (const char* c :
         {"none", "rle", "zips", "zip", "piz", "pxr24", "b44", "b44a", "dwaa", "dwab"})
        for (OIIO::TypeDesc t : {OIIO::TypeDesc::HALF, OIIO::TypeDesc::FLOAT})
            layouts.push_back(
                {std::string(c) + (t == OIIO::TypeDesc::HALF ? "-half" : "-float"), t, c});
    layouts.push_back({"tiled-16", OIIO::TypeDesc::HALF, "zip", 16, 16});
    layouts.push_back({"tiled-odd", OIIO::TypeDesc::FLOAT, "piz", 24, 10});
    layouts.push_back({"tiled-big", OIIO::TypeDesc::FLOAT, "zip", 64, 64});
    layouts.push_back({"window", OIIO::TypeDesc::HALF, "zip", 0, 0, -5, 7});
    layouts.push_back({"decreasing", OIIO::TypeDesc::FLOAT, "zip", 0, 0, 0, 0, true});
    layouts.push_back({"multipart", OIIO::TypeDesc::HALF, "zip", 0, 0, 0, 0, false, true});
    layouts.push_back({"rgbaz", OIIO::TypeDesc::FLOAT, "zip", 0, 0, 0, 0, false, false, 5});
    for (const Layout& l : layouts) {
        const std::string path = dir + "/" + l.name + ".exr";
        auto out = OIIO::ImageOutput::create(path);
        ASSERT_TRUE(out);
        OIIO::ImageSpec spec(w, h, l.channels, l.type);
        spec.x = spec.full_x = l.x; // a picture off the origin, the data window its whole
        spec.y = spec.full_y = l.y;
        spec.tile_width = l.tile_w;
        spec.tile_height = l.tile_h;
        spec.attribute("compression", l.compression);
        if (l.decreasing)
            spec.attribute("openexr:lineOrder", "decreasingY");
        std::vector<float> data(static_cast<size_t>(w) * h * l.channels, 0.25f);
        for (size_t p = 0; p < size_t(w) * h; ++p)
            for (int c = 0; c < 3; ++c)
                data[p * l.channels + c] = px[3 * p + c];
        if (l.multipart) {
            OIIO::ImageSpec specs[2] = {spec, spec};
            specs[1].width = 8; // the display window must be the same in every part
            ASSERT_TRUE(out->open(path, 2, specs)) << out->geterror();
            ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, data.data())) << out->geterror();
            ASSERT_TRUE(out->open(path, specs[1], OIIO::ImageOutput::AppendSubimage))
                << out->geterror();
            ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, data.data(), OIIO::AutoStride,
                                         w * l.channels * sizeof(float)))
                << out->geterror();
        } else {
            ASSERT_TRUE(out->open(path, spec)) << out->geterror();
            ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, data.data())) << out->geterror();
        }
        ASSERT_TRUE(out->close()) << out->geterror();
        out.reset();
        try {
            const et::RgbImage img = et::read_rgb_image(path);
            ASSERT_EQ(img.width, w) << path;
            ASSERT_EQ(img.height, h) << path;
            // The texels OpenImageIO reads from the file itself (lossy methods included).
            auto in = OIIO::ImageInput::open(path);
            ASSERT_TRUE(in) << OIIO::geterror();
            std::vector<float> ref(px.size());
            ASSERT_TRUE(in->read_image(0, 0, 0, 3, OIIO::TypeDesc::FLOAT, ref.data()));
            EXPECT_EQ(img.rgb, ref) << path;
        } catch (const et::Error& e) {
            ADD_FAILURE() << e.what();
        }
    }
    // MIP-mapped textures, as maketx makes them: tiled, every level in the offset table, levels
    // rounded down or up (OpenEXR's level arithmetic, which the walk repeats to size the table).
    for (int rounding : {0, 1}) {
        const std::string tex = dir + "/mip-" + std::to_string(rounding) + ".exr";
        auto out = OIIO::ImageOutput::create(tex);
        ASSERT_TRUE(out);
        OIIO::ImageSpec spec(w, h, 3, OIIO::TypeDesc::HALF);
        spec.tile_width = spec.tile_height = 8;
        spec.attribute("textureformat", "Plain Texture");
        spec.attribute("openexr:roundingmode", rounding);
        ASSERT_TRUE(out->open(tex, spec, OIIO::ImageOutput::Create)) << out->geterror();
        ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, px.data())) << out->geterror();
        // floor(log2(max)) levels below level 0, one more when rounding up a non-power of two.
        const int top = std::max(w, h);
        int levels = 0;
        for (int n = top; n > 1; n >>= 1)
            ++levels;
        const int extra = rounding && (top & (top - 1)) ? 1 : 0;
        for (int l = 1; l <= levels + extra; ++l) {
            auto size = [&](int n) {
                int s = n >> l;
                if (rounding && (s << l) < n)
                    ++s;
                return std::max(s, 1);
            };
            OIIO::ImageSpec level(size(w), size(h), 3, OIIO::TypeDesc::HALF);
            level.tile_width = level.tile_height = 8;
            ASSERT_TRUE(out->open(tex, level, OIIO::ImageOutput::AppendMIPLevel))
                << out->geterror();
            std::vector<float> small(size_t(level.width) * level.height * 3, 1.0f);
            ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, small.data())) << out->geterror();
        }
        ASSERT_TRUE(out->close()) << out->geterror();
        out.reset(); // OpenImageIO flushes the file when the output is destroyed
        try {
            const et::RgbImage img = et::read_rgb_image(tex);
            EXPECT_EQ(img.width, w);
            EXPECT_EQ(img.height, h);
            EXPECT_NEAR(img.rgb[0], px[0], 1e-3 * px[0]) << tex;
        } catch (const et::Error& e) {
            ADD_FAILURE() << e.what();
        }
    }
}
