// host/lib/image/image_io.cpp as a build without OpenImageIO has it (ENVTRACE_OPENIMAGEIO=OFF:
// image_library_none.cpp in place of the oiio_*.cpp files; tests/CMakeLists.txt links the two
// here ahead of the library): PFM read and written as ever, whatever the file is called, and
// every other format refused before anything is read or written, naming the file and the reason.
#include "image/image_io.h"
#include "util/error.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

std::vector<float> ramp(int w, int h) {
    std::vector<float> px(static_cast<size_t>(w) * h * 3);
    for (size_t i = 0; i < px.size(); ++i)
        px[i] = 0.001f * static_cast<float>(i * i) + 0.25f;
    return px;
}

} // namespace

TEST(ImageIoWithoutLibrary, SaysSo) {
    EXPECT_FALSE(et::have_image_library());
}

TEST(ImageIoWithoutLibrary, PfmRoundTripIsExactUnderAnyName) {
    const std::string dir = ett::scratch_dir("image-io-nolib-pfm");
    const int w = 7, h = 5;
    const std::vector<float> px = ramp(w, h);
    et::write_image(dir + "/a.pfm", w, h, 3, px);
    // A converted map keeps its name (scenes refer to it): PFM is known by its magic number.
    fs::copy_file(dir + "/a.pfm", dir + "/map.hdr");
    for (const char* name : {"/a.pfm", "/map.hdr"}) {
        const et::RgbImage img = et::read_rgb_image(dir + name);
        ASSERT_EQ(img.width, w);
        ASSERT_EQ(img.height, h);
        EXPECT_EQ(img.rgb, px) << name;
    }
}

TEST(ImageIoWithoutLibrary, OtherFormatsAreRefusedNamingTheFile) {
    const std::string dir = ett::scratch_dir("image-io-nolib-refused");
    const std::string hdr = dir + "/sky.hdr";
    {
        std::ofstream out(hdr, std::ios::binary);
        out << "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1 +X 1\n" << std::string(4, '\x80');
    }
    const std::string read_error = ett::error_of([&] { et::read_rgb_image(hdr); });
    EXPECT_NE(read_error.find(hdr + ": cannot read image"), std::string::npos) << read_error;
    EXPECT_NE(read_error.find("without OpenImageIO"), std::string::npos) << read_error;
    EXPECT_NE(read_error.find(".pfm"), std::string::npos) << read_error;

    EXPECT_NO_THROW(et::check_writable_format(dir + "/out.pfm"));
    const std::vector<float> px = ramp(2, 2);
    for (const char* name : {"/out.exr", "/out.png", "/out.hdr"}) {
        const std::string path = dir + name;
        const std::string check = ett::error_of([&] { et::check_writable_format(path); });
        EXPECT_NE(check.find(path + ": cannot write"), std::string::npos) << check;
        EXPECT_NE(check.find("without OpenImageIO"), std::string::npos) << check;
        EXPECT_FALSE(ett::error_of([&] { et::write_image(path, 2, 2, 3, px); }).empty()) << name;
        EXPECT_FALSE(fs::exists(path)) << name;
    }
    // Nothing but the input was left behind (no temporaries of the refused writes).
    size_t files = 0;
    for (const auto& e : fs::directory_iterator(dir))
        files += e.is_regular_file();
    EXPECT_EQ(files, 1u);
}
