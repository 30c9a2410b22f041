// Image files (image/image_io.h) and comparison (image/compare.h): EXR keeps floats exactly,
// PNG round-trips through 8-bit sRGB, errors name the file, and compareImages reports the mean,
// max and per-pixel tolerance counts that the accuracy gates rely on.
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <string>

#include "core/error.h"
#include "image/compare.h"
#include "image/image_io.h"
#include "scratch_dir.h"

namespace {

namespace fs = std::filesystem;
using rt::Image;

class ImageIoTest : public ::testing::Test {
  protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ = rt::test::scratchPath(std::string(info->name()) + "/");
    }
    void TearDown() override { fs::remove_all(dir_); }
    fs::path dir_;
};

// A gradient with values outside [0, 1] and a NaN-free spread of magnitudes.
Image gradient(int w, int h) {
    Image img(w, h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            float* p = img.pixel(x, y);
            p[0] = float(x) / (w - 1);
            p[1] = float(y) / (h - 1);
            p[2] = 0.37f * p[0] * p[1] + 1e-4f * float(x * y);
        }
    img.pixel(0, 0)[2] = -0.5f;  // clamps to 0 in PNG
    img.pixel(1, 0)[2] = 3.25f;  // clamps to 1 in PNG
    img.pixel(2, 0)[1] = 1e-7f;  // tiny values survive EXR
    return img;
}

void expectThrowsNaming(const std::function<void()>& fn, const std::string& name) {
    try {
        fn();
        FAIL() << "expected rt::Error mentioning " << name;
    } catch (const rt::Error& e) {
        EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
}

TEST_F(ImageIoTest, ExrRoundTripIsExact) {
    const Image img = gradient(17, 9);
    rt::writeImage(img, dir_ / "g.exr");
    const Image back = rt::readImage(dir_ / "g.exr");
    ASSERT_EQ(back.width, 17);
    ASSERT_EQ(back.height, 9);
    EXPECT_EQ(back.rgb, img.rgb);
}

TEST_F(ImageIoTest, PngRoundTripIsWithinOneSrgbStep) {
    const Image img = gradient(31, 13);
    rt::writeImage(img, dir_ / "g.png");
    const Image back = rt::readImage(dir_ / "g.png");
    ASSERT_EQ(back.width, 31);
    ASSERT_EQ(back.height, 13);
    double maxDiff = 0;
    for (std::size_t i = 0; i < img.rgb.size(); ++i) {
        const double expected = std::clamp(double(img.rgb[i]), 0.0, 1.0);
        maxDiff = std::max(maxDiff, std::abs(expected - back.rgb[i]));
    }
    // Half an 8-bit sRGB step is at most 0.5 * 2.4 / 1.055 / 255 = 1.14/255 in linear (at 1.0).
    EXPECT_LE(maxDiff, 1.0 / 255);
    EXPECT_FLOAT_EQ(back.pixel(0, 0)[2], 0.f);
    EXPECT_FLOAT_EQ(back.pixel(1, 0)[2], 1.f);
}

TEST_F(ImageIoTest, PngStoresSrgbEncodedBytes) {
    // Linear 0.214041 is sRGB 0.5 (byte 128 = 0.50196 -> linear 0.2158605); linear 0.5 is 188.
    Image img(2, 1);
    img.rgb = {0.2158605f, 0.5f, 0.0f, 1.0f, 0.0031308f, 0.05f};
    rt::writeImage(img, dir_ / "s.png");
    // Reading decodes sRGB, so the values must land exactly on the decoded codes.
    const Image back = rt::readImage(dir_ / "s.png");
    auto decode = [](int code) {
        const double s = code / 255.0;
        return s <= 0.04045 ? s / 12.92 : std::pow((s + 0.055) / 1.055, 2.4);
    };
    EXPECT_NEAR(back.rgb[0], decode(128), 1e-6);
    EXPECT_NEAR(back.rgb[1], decode(188), 1e-6);
    EXPECT_NEAR(back.rgb[2], 0.0, 1e-7);
    EXPECT_NEAR(back.rgb[3], 1.0, 1e-7);
    EXPECT_NEAR(back.rgb[4], decode(10), 1e-6);  // 12.92 * 0.0031308 * 255 = 10.3
    EXPECT_NEAR(back.rgb[5], decode(63), 1e-6);  // 1.055 * 0.05^(1/2.4) - 0.055 = 0.2474
}

// Writes a file with any channel count straight through OIIO.
void writeRaw(const fs::path& path, int w, int h, int channels, OIIO::TypeDesc type,
              const void* data) {
    auto out = OIIO::ImageOutput::create(path.string());
    ASSERT_TRUE(out);
    ASSERT_TRUE(out->open(path.string(), OIIO::ImageSpec(w, h, channels, type)));
    ASSERT_TRUE(out->write_image(type, data));
    ASSERT_TRUE(out->close());
}

TEST_F(ImageIoTest, GrayFilesAreReplicatedToRgb) {
    const std::uint8_t gray[6] = {0, 51, 128, 188, 230, 255};
    writeRaw(dir_ / "gray.png", 3, 2, 1, OIIO::TypeDesc::UINT8, gray);
    const Image back = rt::readImage(dir_ / "gray.png");
    ASSERT_EQ(back.width, 3);
    ASSERT_EQ(back.height, 2);
    ASSERT_EQ(back.rgb.size(), std::size_t(18));
    const double s = 128 / 255.0, linear128 = std::pow((s + 0.055) / 1.055, 2.4);
    for (int c = 0; c < 3; ++c) {
        EXPECT_FLOAT_EQ(back.pixel(0, 0)[c], 0.f);
        EXPECT_NEAR(back.pixel(2, 0)[c], linear128, 1e-6);
        EXPECT_FLOAT_EQ(back.pixel(2, 1)[c], 1.f);
    }
}

TEST_F(ImageIoTest, RgbaFilesDropAlpha) {
    const float rgba[8] = {0.25f, 0.5f, 2.0f, 0.1f, -1.0f, 0.0f, 0.75f, 0.9f};
    writeRaw(dir_ / "rgba.exr", 2, 1, 4, OIIO::TypeDesc::FLOAT, rgba);
    const Image back = rt::readImage(dir_ / "rgba.exr");
    ASSERT_EQ(back.rgb.size(), std::size_t(6));
    EXPECT_EQ(back.rgb, (std::vector<float>{0.25f, 0.5f, 2.0f, -1.0f, 0.0f, 0.75f}));
}

TEST_F(ImageIoTest, UnknownExtensionThrows) {
    expectThrowsNaming([&] { rt::writeImage(gradient(4, 4), dir_ / "g.notaformat"); },
                       "g.notaformat");
    expectThrowsNaming([&] { rt::writeImage(gradient(4, 4), dir_ / "noextension"); },
                       "noextension");
}

TEST_F(ImageIoTest, UnwritablePathThrows) {
    expectThrowsNaming([&] { rt::writeImage(gradient(4, 4), dir_); }, dir_.filename().string());
    expectThrowsNaming([&] { rt::writeImage(gradient(4, 4), dir_ / "missing" / "dir" / "g.png"); },
                       "g.png");
}

TEST_F(ImageIoTest, UnreadableFilesThrow) {
    expectThrowsNaming([&] { rt::readImage(dir_ / "absent.png"); }, "absent.png");
    std::ofstream(dir_ / "garbage.png") << "this is not a png";
    expectThrowsNaming([&] { rt::readImage(dir_ / "garbage.png"); }, "garbage.png");
    expectThrowsNaming([&] { rt::readImage(dir_); }, dir_.filename().string());
}

// --- compareImages ----------------------------------------------------------------------------

Image constant(int w, int h, float v) {
    Image img(w, h);
    std::fill(img.rgb.begin(), img.rgb.end(), v);
    return img;
}

TEST(CompareImages, IdenticalImagesHaveNoDifference) {
    const Image img = gradient(16, 8);
    const rt::ImageDiff d = rt::compareImages(img, img, 0.0);
    EXPECT_EQ(d.meanAbs, 0);
    EXPECT_EQ(d.maxAbs, 0);
    EXPECT_EQ(d.rmse, 0);
    EXPECT_EQ(d.fractionWithin, 1);
    EXPECT_EQ(d.pixelsOver, 0);
}

TEST(CompareImages, KnownDifferencesGiveExpectedStatistics) {
    // 10x10 image; 4 pixels differ in one channel by 3/255, 1 pixel in all channels by 1/255.
    Image a = constant(10, 10, 0.5f), b = a;
    for (int i = 0; i < 4; ++i) b.pixel(i, 0)[1] += 3.f / 255;
    for (int c = 0; c < 3; ++c) b.pixel(9, 9)[c] -= 1.f / 255;
    const rt::ImageDiff d = rt::compareImages(a, b, 2.0 / 255);
    const double total = 4 * 3.0 / 255 + 3 * 1.0 / 255;
    EXPECT_NEAR(d.meanAbs, total / 300, 1e-7);
    EXPECT_NEAR(d.maxAbs, 3.0 / 255, 1e-6);
    EXPECT_NEAR(d.rmse, std::sqrt((4 * 9.0 + 3 * 1.0) / (255.0 * 255) / 300), 1e-6);
    EXPECT_EQ(d.pixelsOver, 4);
    EXPECT_DOUBLE_EQ(d.fractionWithin, 0.96);
    // A looser tolerance accepts everything.
    EXPECT_EQ(rt::compareImages(a, b, 4.0 / 255).pixelsOver, 0);
}

TEST(CompareImages, ClampsToUnitUnlessAskedNotTo) {
    const Image a = constant(4, 4, 1.5f), b = constant(4, 4, 1.0f);
    const rt::ImageDiff clamped = rt::compareImages(a, b, 0.0);
    EXPECT_EQ(clamped.maxAbs, 0);
    EXPECT_EQ(clamped.pixelsOver, 0);
    const rt::ImageDiff raw = rt::compareImages(a, b, 0.1, false);
    EXPECT_NEAR(raw.maxAbs, 0.5, 1e-7);
    EXPECT_NEAR(raw.meanAbs, 0.5, 1e-7);
    EXPECT_EQ(raw.pixelsOver, 16);
    EXPECT_EQ(raw.fractionWithin, 0);
    // Negative values clamp to 0 as well.
    EXPECT_EQ(rt::compareImages(constant(3, 3, -2.f), constant(3, 3, 0.f), 0.0).maxAbs, 0);
}

// A clamp would turn NaN into 0 and +Inf into 1, so a frame full of NaN would match a black one.
// Non-finite pixels are counted before any clamp and fail every comparison, clamped or raw.
TEST(CompareImages, NonFinitePixelsAreNeverHidden) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    for (bool clamp : {true, false}) {
        const Image black = constant(4, 4, 0.f);
        const rt::ImageDiff allNan = rt::compareImages(constant(4, 4, nan), black, 0.5, clamp);
        EXPECT_EQ(allNan.nonfinite, 16) << "clamp " << clamp;
        EXPECT_EQ(allNan.pixelsOver, 16);
        EXPECT_EQ(allNan.fractionWithin, 0);
        EXPECT_TRUE(std::isinf(allNan.maxAbs));
        EXPECT_TRUE(std::isinf(allNan.meanAbs));
        EXPECT_FALSE(allNan.allWithin());

        Image one = constant(4, 4, 1.f), withInf = one;
        withInf.pixel(2, 1)[0] = inf;
        withInf.pixel(3, 3)[2] = -inf;
        const rt::ImageDiff d = rt::compareImages(withInf, one, 0.5, clamp);
        EXPECT_EQ(d.nonfinite, 2);
        EXPECT_EQ(d.pixelsOver, 2);
        EXPECT_DOUBLE_EQ(d.fractionWithin, 14.0 / 16);
        EXPECT_FALSE(d.allWithin());
        // Both images NaN at the same place still fail: NaN is no value to agree on.
        EXPECT_EQ(rt::compareImages(withInf, withInf, 1.0, clamp).nonfinite, 2);
    }
    Image mixed = constant(3, 2, 0.25f);
    mixed.pixel(0, 0)[1] = nan;
    mixed.pixel(1, 1)[0] = inf;
    mixed.pixel(1, 1)[2] = -inf;  // Inf - Inf in one pixel: still one pixel
    EXPECT_EQ(rt::countNonFinite(mixed), 2);
    EXPECT_EQ(rt::countNonFinite(constant(3, 2, 0.25f)), 0);
    EXPECT_TRUE(rt::compareImages(constant(3, 2, 0.25f), constant(3, 2, 0.25f), 0.0).allWithin());
}

TEST(CompareImages, SizeMismatchThrows) {
    EXPECT_THROW(rt::compareImages(constant(4, 4, 0), constant(4, 5, 0), 0.01), rt::Error);
    EXPECT_THROW(rt::compareImages(constant(5, 4, 0), constant(4, 4, 0), 0.01), rt::Error);
}

}  // namespace
