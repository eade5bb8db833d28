// Images read through OpenImageIO (image_library.h): every format it reads, checked first
// (oiio_format_checks.h, exr_header.h), decoded a band of rows at a time; Radiance pixels
// decoded here (oiio_rgbe_decoder.h).
#include "image/exr_header.h"
#include "image/image_io.h"
#include "image/image_library.h"
#include "image/oiio_file_proxy.h"
#include "image/oiio_format_checks.h"
#include "image/oiio_rgbe_decoder.h"
#include "util/error.h"
#include "util/file_check.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cctype>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <unistd.h>

OIIO_NAMESPACE_USING

namespace et::image_detail {
namespace {

bool starts_with(const std::string& path, const char* magic) {
    char head[8] = {};
    const size_t n = std::strlen(magic);
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (!f)
        return false;
    const bool ok = std::fread(head, 1, n, f) == n && std::memcmp(head, magic, n) == 0;
    std::fclose(f);
    return ok;
}

// "R, G" (at most 8 names) for messages.
std::string channel_list(const ImageSpec& spec) {
    std::string out;
    for (int c = 0; c < spec.nchannels && c < 8; ++c)
        out += (c ? ", " : "") + spec.channelnames[static_cast<size_t>(c)];
    return out + (spec.nchannels > 8 ? ", ..." : "");
}

// An image OpenImageIO reads, decoded a band of rows at a time.
struct OiioSource final : RowSource {
    std::unique_ptr<BufferedFileProxy> proxy; // outlives `in`, which reads through it
    std::unique_ptr<ImageInput> in;
    ImageSpec spec;
    int idx[3] = {0, 0, 0}; // the channels that become R, G, B
    int lo = 0, hi = 0;     // the range of channels decoded
    bool direct = false;    // float R, G, B adjacent: decoded straight into the texels
    bool decode_srgb = false;
    bool row_by_row = false;            // scanlines one at a time (TIFF MinIsWhite, F8)
    std::vector<unsigned char> scratch; // one band of the decoded channels otherwise
    std::unique_ptr<RgbeDecoder> rgbe;  // Radiance pixels, decoded here

    OiioSource(const std::string& path, uint64_t file_bytes, bool colour);
    int width() const override { return spec.width; }
    int height() const override { return spec.height; }
    int band_rows() const override;
    void read_rows(const std::string& path, int y0, int y1, float* dst) override;
    void finish() override { in->close(); }
};

OiioSource::OiioSource(const std::string& path, uint64_t file_bytes, bool colour) {
    // PNG, TIFF, TGA, ... colour as stored: OpenImageIO would otherwise multiply it by an
    // unassociated alpha, and a map's texels are radiance whatever its alpha says.
    ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    if (starts_with(path, "\x76\x2f\x31\x01")) { // OpenEXR, whatever the file is called
        // Every header walked before OpenEXR allocates what it claims (F10, F11), and the first
        // part's size checked against the budget before OpenEXR sizes its tables by it.
        const ExrHeaderInfo exr = check_exr_header(path, file_bytes);
        check_declared_size(path, exr.width, exr.height, 1, exr.stored_bytes, file_bytes);
    }
    check_pnm_maxval(path);
    if (starts_with(path, "#?")) { // Radiance HDR, read through our buffered proxy
        const std::vector<std::string> header = radiance_header(path);
        warn_radiance_exposure(path, header);
        if (radiance_format(header) == "32-bit_rle_xyze")
            throw Error(path + ": Radiance XYZE pixels (CIE XYZ) are not read; write the map as "
                               "RGBE (Radiance's ra_xyze -r IN OUT) or as OpenEXR");
        proxy = std::make_unique<BufferedFileProxy>(path, file_bytes);
        Filesystem::IOProxy* p = proxy.get();
        ImageSpec hdr_config = config;
        hdr_config.attribute("oiio:ioproxy", TypeDesc::PTR, &p);
        in = ImageInput::create("hdr");
        ImageSpec opened;
        if (!proxy->opened() || !in || !in->supports("ioproxy") ||
            !in->open(path, opened, hdr_config)) {
            in.reset(); // left to the general open below, which tries every reader
            proxy.reset();
            (void)OIIO::geterror();
        } else {
            // The header read, the proxy stands at the first scanline.
            rgbe = std::make_unique<RgbeDecoder>(path, proxy->tell(), opened.width);
            if (!rgbe->opened())
                rgbe.reset();
        }
    }
    if (!in)
        in = ImageInput::open(path, &config);
    if (!in)
        throw Error(path + ": cannot read image: " + one_line(OIIO::geterror()));
    spec = in->spec();
    const int w = spec.width, h = spec.height, nch = spec.nchannels;
    if (nch <= 0)
        throw Error(path + ": image has no channels");
    if (spec.deep)
        throw Error(path + ": deep images are not supported");
    check_declared_size(path, w, h, spec.depth, spec.image_bytes(true), file_bytes);
    const bool exr = std::string(in->format_name()) == "openexr";
    check_upright_and_whole(path, spec, exr);

    // Which channels become R, G, B.
    idx[1] = nch > 1 ? 1 : 0;
    idx[2] = nch > 2 ? 2 : 0;
    if (nch == 2)
        idx[1] = idx[2] = 0; // grey + alpha
    int r = spec.channelindex("R"), g = spec.channelindex("G"), b = spec.channelindex("B");
    // A layered EXR's colour (Blender's "Image.R", "Image.G", "Image.B"): the first layer that
    // has all three. EXR stores channels sorted by name, so the first three in file order were B,
    // G and R: the map's colours swapped without a word.
    if (exr && !(r >= 0 && g >= 0 && b >= 0))
        for (int c = 0; c < nch; ++c) {
            const std::string& n = spec.channelnames[static_cast<size_t>(c)];
            if (n.size() < 2 || n.compare(n.size() - 2, 2, ".R"))
                continue;
            const std::string layer = n.substr(0, n.size() - 1);
            const int lg = spec.channelindex(layer + "G"), lb = spec.channelindex(layer + "B");
            if (lg >= 0 && lb >= 0) {
                r = c;
                g = lg;
                b = lb;
                break;
            }
        }
    if (r >= 0 && g >= 0 && b >= 0) {
        idx[0] = r;
        idx[1] = g;
        idx[2] = b;
    }
    if (exr) {
        // An EXR names what its channels hold: one without colour or luminance names (depth,
        // alpha, XYZ, a vector) is read as colour from the first channels, and said so.
        const int y = spec.channelindex("Y");
        if (!(r >= 0 && g >= 0 && b >= 0) && r < 0 && g < 0 && b < 0) {
            if (y >= 0 && nch > 1 && spec.channelindex("X") < 0) {
                idx[0] = idx[1] = idx[2] = y; // luminance with others (alpha): grey from Y
            } else if (y < 0 || nch > 1) {
                std::string used;
                for (int k = 0; k < (nch > 2 ? 3 : 1); ++k)
                    used += (k ? ", " : "") + spec.channelnames[static_cast<size_t>(idx[k])];
                warn(path + ": no channels named as colour (R, G, B)" +
                     (y < 0 ? " or luminance (Y)" : "") + " among " + channel_list(spec) +
                     "; read " + used + " as " + (nch > 2 ? "red, green and blue" : "grey"));
            }
        }
        for (int k = 0; k < 3; ++k) {
            const TypeDesc t = spec.channelformat(idx[k]);
            if (t.basetype == TypeDesc::UINT32 || t.basetype == TypeDesc::INT32) {
                warn(path + ": channel '" + spec.channelnames[static_cast<size_t>(idx[k])] +
                     "' holds integers (an EXR's ids, not light); read scaled to [0, 1]");
                break;
            }
        }
        // A multi-part EXR: the first part is read, and said (a render's passes may come first).
        if (in->seek_subimage(1, 0)) {
            int parts = 2;
            while (parts < 64 && in->seek_subimage(parts, 0))
                ++parts;
            warn(path + ": " + std::to_string(parts) + (parts == 64 ? " or more" : "") +
                 " parts; the first (channels " + channel_list(spec) +
                 ") is read, the others ignored");
            if (!in->seek_subimage(0, 0))
                throw Error(path + ": cannot read image: " + one_line(in->geterror()));
        }
    }
    // An EXR's channels named as colour but not all three ("R, G"): read as grey from the first,
    // which is not the picture -- said once, not silently. (Other readers name unnamed channels
    // R, G, ... themselves: a grey + alpha TIFF would read as "R, G".)
    if (exr && !(r >= 0 && g >= 0 && b >= 0) && (g >= 0 || b >= 0))
        warn(path + ": has colour channels but not all of R, G and B (" + channel_list(spec) +
             "); read as grey from channel '" + spec.channelnames[static_cast<size_t>(idx[0])] +
             "'");
    lo = std::min({idx[0], idx[1], idx[2]});
    hi = std::max({idx[0], idx[1], idx[2]}) + 1;
    const std::string cs = spec.get_string_attribute("oiio:ColorSpace");
    const bool integer =
        spec.format.basetype == TypeDesc::UINT8 || spec.format.basetype == TypeDesc::UINT16;
    decode_srgb = colour && integer && cs != "Linear" && cs != "linear";
    direct = spec.tile_width == 0 && spec.format == TypeDesc::FLOAT &&
             spec.channelformats.empty() && idx[0] == lo && idx[1] == lo + 1 && idx[2] == lo + 2;
    // OpenImageIO 2.4's TIFF reader decodes a range of whole strips itself (zip, 8 or 16 bits,
    // contiguous channels) and then, for PhotometricInterpretation MinIsWhite (0), inverts
    // nchannels times too many values per strip, past the end of the buffer: a 191-byte file
    // crashed the CLI (fuzz finding F8). Single scanlines go through libtiff's scanline path,
    // which inverts the right count, so such files are read a row at a time.
    row_by_row = spec.tile_width == 0 && nch > 1 && std::string(in->format_name()) == "tiff" &&
                 spec.get_int_attribute("tiff:PhotometricInterpretation", -1) == 0;
}

int OiioSource::band_rows() const {
    // EXR in whole compression blocks (DWAB's 256 lines are the most), tiles and TIFF strips
    // whole, so that no block is decoded twice; other formats in bands of about 4 MB of texels,
    // which the caller then sanitises while they are still in cache.
    const int unit = spec.tile_width > 0 ? std::max(1, spec.tile_height)
                                         : spec.get_int_attribute("tiff:RowsPerStrip", 0);
    const int64_t row_bytes = 3 * sizeof(float) * static_cast<int64_t>(spec.width);
    int rows = std::string(in->format_name()) == "openexr"
                   ? 256
                   : static_cast<int>(std::clamp<int64_t>((4 << 20) / row_bytes, 1, 256));
    if (unit > 0 && unit <= spec.height)
        rows = (rows + unit - 1) / unit * unit;
    // At most 64 MB of texels a band (whole blocks where they fit; a 16384-wide map keeps its
    // 256-row bands): the reader touches memory a band ahead of the data, so a header that
    // declares a very wide image its file cannot hold (a 25 kB EXR claiming 1048640x32, one
    // 403 MB band) fails having touched one band, not the whole image (F7's class).
    const int max_rows = static_cast<int>(std::max<int64_t>(1, (int64_t(64) << 20) / row_bytes));
    if (rows > max_rows)
        rows = unit > 0 && max_rows >= unit ? max_rows / unit * unit : max_rows;
    return std::max(1, std::min(rows, spec.height));
}

void OiioSource::read_rows(const std::string& path, int y0, int y1, float* dst) {
    if (row_by_row && y1 - y0 > 1) {
        for (int y = y0; y < y1; ++y)
            read_rows(path, y, y + 1, dst + static_cast<size_t>(y - y0) * spec.width * 3);
        return;
    }
    const int w = spec.width, rows = y1 - y0;
    const int ybegin = spec.y + y0, yend = spec.y + y1;
    const stride_t xstride = 3 * sizeof(float), ystride = xstride * w;
    auto fail = [&] { throw Error(path + ": cannot decode image: " + one_line(in->geterror())); };
    if (rgbe) {
        const std::string err = rgbe->read_rows(y0, y1, dst);
        if (!err.empty())
            throw Error(path + ": cannot decode image: " + err);
    } else if (direct) {
        // Native float pixels are the texels: no conversion, no temporary (read_scanlines would
        // allocate and fill a 64 MB buffer per call, then copy).
        if (!in->read_native_scanlines(0, 0, ybegin, yend, spec.z, lo, lo + 3, dst))
            fail();
    } else if (spec.tile_width > 0) {
        // Whole rows of tiles come converted to float; the rows asked for are copied out.
        const int th = std::max(1, spec.tile_height), n = hi - lo;
        const int t0 = y0 / th * th, t1 = std::min(spec.height, (y1 + th - 1) / th * th);
        scratch.resize(static_cast<size_t>(w) * (t1 - t0) * n * sizeof(float));
        const float* band = reinterpret_cast<float*>(scratch.data());
        if (!in->read_tiles(0, 0, spec.x, spec.x + w, spec.y + t0, spec.y + t1, spec.z, spec.z + 1,
                            lo, hi, TypeDesc::FLOAT, scratch.data()))
            fail();
        band += static_cast<size_t>(y0 - t0) * w * n;
        for (size_t p = 0, np = static_cast<size_t>(w) * rows; p < np; ++p)
            for (int c = 0; c < 3; ++c)
                dst[3 * p + c] = band[n * p + (idx[c] - lo)];
    } else {
        // Native pixels of channels [lo, hi) into the band buffer, then converted per channel
        // (channels may differ in type) into the RGB stride.
        const stride_t pixel = static_cast<stride_t>(spec.pixel_bytes(lo, hi, true));
        scratch.resize(static_cast<size_t>(pixel) * w * rows);
        if (!in->read_native_scanlines(0, 0, ybegin, yend, spec.z, lo, hi, scratch.data()))
            fail();
        for (int c = 0; c < 3; ++c) {
            const int ch = idx[c];
            const TypeDesc type = spec.channelformat(ch);
            const unsigned char* src = scratch.data() + spec.pixel_bytes(lo, ch, true);
            if (!convert_image(1, w, rows, 1, src, type, pixel, pixel * w, AutoStride, dst + c,
                               TypeDesc::FLOAT, xstride, ystride, AutoStride))
                throw Error(path + ": cannot convert pixels of type " + type.c_str());
        }
    }
    if (decode_srgb)
        for (size_t i = 0, n = static_cast<size_t>(w) * rows * 3; i < n; ++i)
            dst[i] = srgb_to_linear(dst[i]);
}

} // namespace

bool library_available() {
    return true;
}

std::unique_ptr<RowSource> open_with_library(const std::string& path, uint64_t file_bytes,
                                             bool colour) {
    return std::make_unique<OiioSource>(path, file_bytes, colour);
}

} // namespace et::image_detail
