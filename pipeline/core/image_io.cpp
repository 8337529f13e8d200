#include "core/image_io.h"

#include "core/atomic_file.h"
#include "core/error.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace vl {

float srgbToLinear(float c) {
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

float linearToSrgb(float c) {
    return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

namespace {

void writeWith(const std::string& path, const OIIO::ImageSpec& spec, const void* data) {
    writeAtomically(path, [&](const std::string& temp) {
        auto out = OIIO::ImageOutput::create(temp);
        if (!out) throw Error("cannot write " + path + ": " + OIIO::geterror());
        if (!out->open(temp, spec) || !out->write_image(spec.format, data) || !out->close())
            throw Error("cannot write " + path + ": " + out->geterror());
    });
}

}  // namespace

void writeExr(const Image& image, const std::string& path, const std::vector<std::string>& channelNames) {
    OIIO::ImageSpec spec(image.width, image.height, image.channels, OIIO::TypeDesc::FLOAT);
    if (!channelNames.empty()) {
        if (static_cast<int>(channelNames.size()) != image.channels)
            throw Error("writeExr: " + path + ": channel name count does not match the image");
        spec.channelnames = channelNames;
    }
    // Run-length: a bake's float images hold noise in their low bits that zip cannot squeeze,
    // so zip costs time for almost no bytes; both are lossless, and runs still fold masks' and
    // padding's flat spans (docs/decisions.md, "Image compression").
    spec.attribute("compression", "rle");
    // OpenImageIO stamps an EXR with the time it was written (capDate) unless told one: an empty
    // one keeps a bake's files the same bytes from run to run.
    spec.attribute("DateTime", "");
    writeWith(path, spec, image.pixels.data());
}

void writePngSrgb(const Image& image, const std::string& path) {
    const int outChannels = std::min(image.channels, 4);
    std::vector<uint8_t> bytes(static_cast<size_t>(image.width) * image.height * outChannels);
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x)
            for (int c = 0; c < outChannels; ++c) {
                float v = image.at(x, y, c);
                if (c < 3) v = linearToSrgb(std::max(v, 0.0f));
                if (!(v >= 0.0f)) v = 0.0f;
                bytes[(static_cast<size_t>(y) * image.width + x) * outChannels + c] =
                    static_cast<uint8_t>(std::lround(std::min(v, 1.0f) * 255.0f));
            }
    OIIO::ImageSpec spec(image.width, image.height, outChannels, OIIO::TypeDesc::UINT8);
    // zlib level 3, not the default 6: much faster for slightly larger files, the
    // same pixels (docs/decisions.md, "Image compression").
    spec.attribute("png:compressionLevel", 3);
    writeWith(path, spec, bytes.data());
}

namespace {

// The file's pixels as float; `storedAsFloat` says whether the file held floats.
Image readFloats(const std::string& path, bool& storedAsFloat) {
    auto in = OIIO::ImageInput::open(path);
    if (!in) throw InputError("cannot read image " + path + ": " + OIIO::geterror());
    const OIIO::ImageSpec& spec = in->spec();
    Image image(spec.width, spec.height, spec.nchannels);
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, image.pixels.data()))
        throw InputError("cannot read image " + path + ": " + in->geterror());
    storedAsFloat = spec.format.is_floating_point();
    return image;
}

}  // namespace

Image readImage(const std::string& path) {
    bool storedAsFloat = false;
    return readFloats(path, storedAsFloat);
}

Image readLinearImage(const std::string& path) {
    bool storedAsFloat = false;
    Image image = readFloats(path, storedAsFloat);
    if (storedAsFloat) return image;
    const int colourChannels = std::min(image.channels, 3);  // alpha stays as stored
    for (size_t k = 0; k < image.pixels.size(); ++k)
        if (int(k % size_t(image.channels)) < colourChannels) image.pixels[k] = srgbToLinear(image.pixels[k]);
    return image;
}


std::vector<uint8_t> encodePng8(int width, int height, int channels, const std::vector<uint8_t>& texels) {
    if (width <= 0 || height <= 0 || channels < 1 || channels > 4 ||
        texels.size() != static_cast<size_t>(width) * static_cast<size_t>(height) * static_cast<size_t>(channels))
        throw Error("encodePng8: " + std::to_string(texels.size()) + " bytes for " + std::to_string(width) + " x " +
                    std::to_string(height) + " x " + std::to_string(channels));
    std::vector<uint8_t> png;
    OIIO::Filesystem::IOVecOutput memory(png);
    OIIO::ImageSpec spec(width, height, channels, OIIO::TypeDesc::UINT8);
    spec.attribute("oiio:UnassociatedAlpha", 1);
    auto out = OIIO::ImageOutput::create("png");
    if (!out) throw Error("encodePng8: no PNG writer: " + OIIO::geterror());
    out->set_ioproxy(&memory);
    if (!out->open("memory.png", spec) || !out->write_image(OIIO::TypeDesc::UINT8, texels.data()) || !out->close())
        throw Error("encodePng8: " + out->geterror());
    return png;
}

namespace {

// The 8-bit texels of an opened image as stored; InputError naming `what`.
std::vector<uint8_t> readTexels8(OIIO::ImageInput& in, const OIIO::ImageSpec& spec, const std::string& what, int& width,
                                 int& height, int& channels) {
    width = spec.width;
    height = spec.height;
    channels = spec.nchannels;
    std::vector<uint8_t> texels(static_cast<size_t>(width) * static_cast<size_t>(height) * static_cast<size_t>(channels));
    if (!in.read_image(0, 0, 0, channels, OIIO::TypeDesc::UINT8, texels.data()))
        throw InputError(what + ": " + in.geterror());
    return texels;
}

}  // namespace

std::vector<uint8_t> decodeImage8(const std::vector<uint8_t>& bytes, const std::string& what, int& width, int& height,
                                  int& channels) {
    OIIO::Filesystem::IOMemReader memory(const_cast<uint8_t*>(bytes.data()), bytes.size());
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    auto in = OIIO::ImageInput::create("png");
    OIIO::ImageSpec spec;
    if (!in || !in->set_ioproxy(&memory) || !in->open("memory.png", spec, config))
        throw InputError("cannot decode " + what + ": " + (in ? in->geterror() : OIIO::geterror()));
    return readTexels8(*in, spec, "cannot decode " + what, width, height, channels);
}

std::vector<uint8_t> readImage8(const std::string& path, int& width, int& height, int& channels) {
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    auto in = OIIO::ImageInput::open(path, &config);
    if (!in) throw InputError("cannot read image " + path + ": " + OIIO::geterror());
    return readTexels8(*in, in->spec(), "cannot read image " + path, width, height, channels);
}

}  // namespace vl
