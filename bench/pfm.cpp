// rtlab bench — .pfm reading and writing. PFM stores rows bottom first; Image keeps the top row
// first, so rows are flipped on the way in and out. A negative scale means little-endian.
#include "bench/pfm.h"

#include <bit>
#include <cstring>
#include <fstream>
#include <string>

#include "core/error.h"

namespace rt::bench {

static_assert(std::endian::native == std::endian::little, "PFM is written little-endian");

void writePfm(const Image& image, const std::filesystem::path& path) {
    std::ofstream f(path, std::ios::binary);
    if (!f) throw Error(path.string() + ": cannot write");
    f << "PF\n" << image.width << ' ' << image.height << "\n-1.0\n";
    const std::streamsize row = std::streamsize(image.width) * 3 * sizeof(float);
    for (int y = image.height - 1; y >= 0; --y)
        f.write(reinterpret_cast<const char*>(image.pixel(0, y)), row);
    if (!f) throw Error(path.string() + ": write failed (disk full?)");
}

Image readPfm(const std::filesystem::path& path) {
    std::ifstream f(path, std::ios::binary);
    if (!f) throw Error(path.string() + ": cannot read");
    std::string magic;
    int width = 0, height = 0;
    double scale = 0;
    f >> magic >> width >> height >> scale;
    f.get();  // the single whitespace byte before the data
    if (!f || magic != "PF" || width <= 0 || height <= 0 || width > 65536 || height > 65536)
        throw Error(path.string() + ": not an RGB PFM file (expected a 'PF' header)");
    if (scale >= 0) throw Error(path.string() + ": big-endian PFM is not supported");
    Image image(width, height);
    const std::streamsize row = std::streamsize(width) * 3 * sizeof(float);
    for (int y = height - 1; y >= 0; --y) f.read(reinterpret_cast<char*>(image.pixel(0, y)), row);
    if (!f)
        throw Error(path.string() + ": file ends before its " + std::to_string(width) + "x" +
                    std::to_string(height) + " pixels");
    return image;
}

}  // namespace rt::bench
