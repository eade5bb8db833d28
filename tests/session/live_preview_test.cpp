// The live preview (session/render_outputs.h, LivePreview) while a session renders: after each
// due round the PNG preview and the linear image on disk are whole, readable images of the film
// so far (the EXR's spp says which round), and no temporary is left beside them.
#include "single_cluster.h"
#include "render_util.h"
#include "session/render_outputs.h"
#include "session/render_session.h"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

namespace fs = std::filesystem;

namespace {

std::unique_ptr<et::PreparedRender> prepared_room(int spp) {
    et::Scene s = ett::side_lit_room(12, 9);
    s.settings.backend = et::Backend::cpu;
    s.settings.threads = 2;
    s.settings.spp = spp;
    s.settings.max_depth = 3;
    const et::RenderSettings st = s.settings;
    return et::prepare_render(std::move(s), st);
}

// The pixels as a viewer reads them (OpenImageIO directly: et::read_rgb_image would record the
// file as an input of this process, which no later write may then replace).
std::vector<float> pixels(const std::string& path, int& width, int& height) {
    auto in = OIIO::ImageInput::open(path);
    if (!in)
        return {};
    width = in->spec().width;
    height = in->spec().height;
    std::vector<float> px(size_t(width) * height * in->spec().nchannels);
    if (!in->read_image(0, 0, 0, -1, OIIO::TypeDesc::FLOAT, px.data()))
        return {};
    return px;
}

int spp_of(const std::string& exr) {
    auto in = OIIO::ImageInput::open(exr);
    return in ? std::stoi(in->spec().get_string_attribute("envtrace:spp", "-1")) : -1;
}

// Files in `dir` other than `keep`: a temporary left behind would be one.
std::vector<std::string> others(const std::string& dir, const std::vector<std::string>& keep) {
    std::vector<std::string> out;
    for (const auto& e : fs::directory_iterator(dir))
        if (std::find(keep.begin(), keep.end(), e.path().string()) == keep.end())
            out.push_back(e.path().filename().string());
    return out;
}

TEST(LivePreview, WritesWholeImagesOfTheFilmSoFarWhileRendering) {
    const std::string dir = ett::scratch_dir("live_preview");
    et::RenderOutputs o;
    o.image = dir + "/out.exr";
    o.preview = dir + "/out.png";
    o.live_interval = 0.0; // after every round
    o.live_image = true;
    const auto p = prepared_room(5);
    et::RenderSession session(ett::single_cluster(), *p, {});
    session.start();
    et::LivePreview live(o, session);
    et::SessionCallbacks cb;
    int checked = 0;
    cb.progress = [&](int spp, double seconds) {
        live.update(spp, seconds);
        // What a viewer opening the files now would read: whole images of this round's film.
        int w = 0, h = 0;
        EXPECT_EQ(pixels(o.preview, w, h).size(), 12u * 9 * 3);
        EXPECT_EQ(w, 12);
        EXPECT_EQ(h, 9);
        EXPECT_EQ(pixels(o.image, w, h), session.renderer().sums().mean()) << "at " << spp;
        EXPECT_EQ(spp_of(o.image), spp);
        EXPECT_TRUE(others(dir, {o.image, o.preview}).empty());
        ++checked;
    };
    const et::SessionResult r = session.run(cb);
    EXPECT_EQ(r.spp, 5);
    EXPECT_EQ(checked, 5);
    EXPECT_EQ(live.writes(), 5);
}

// An interval longer than the render: one preview, after the first round, and no more.
TEST(LivePreview, WritesOnlyWhenDue) {
    const std::string dir = ett::scratch_dir("live_preview_due");
    et::RenderOutputs o;
    o.image = dir + "/out.exr";
    o.preview = dir + "/out.png";
    o.live_interval = 1e6;
    const auto p = prepared_room(3);
    et::RenderSession session(ett::single_cluster(), *p, {});
    session.start();
    et::LivePreview live(o, session);
    et::SessionCallbacks cb;
    cb.progress = [&](int spp, double seconds) { live.update(spp, seconds); };
    session.run(cb);
    EXPECT_EQ(live.writes(), 1);
    EXPECT_TRUE(fs::exists(o.preview));
    EXPECT_FALSE(fs::exists(o.image)) << "the linear image only with live_image";
}

// A preview that cannot be written is warned about once and stops the live previews, not the
// render.
TEST(LivePreview, AFailedWriteWarnsAndTheRenderGoesOn) {
    const std::string dir = ett::scratch_dir("live_preview_fails");
    et::RenderOutputs o;
    o.image = dir + "/out.exr";
    o.preview = dir + "/gone/out.png"; // a folder that is not there
    o.live_interval = 0.0;
    const auto p = prepared_room(3);
    et::RenderSession session(ett::single_cluster(), *p, {});
    session.start();
    et::LivePreview live(o, session);
    et::SessionCallbacks cb;
    cb.progress = [&](int spp, double seconds) { live.update(spp, seconds); };
    ett::WarningCapture warnings;
    const et::SessionResult r = session.run(cb);
    EXPECT_EQ(r.spp, 3);
    EXPECT_EQ(live.writes(), 1);
    ASSERT_EQ(warnings.messages().size(), 1u);
    EXPECT_NE(warnings.messages()[0].find("no more live previews"), std::string::npos);
}

} // namespace
