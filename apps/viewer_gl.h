// rtlab-view — the OpenGL 3.3 core side of the viewer: a full-window textured quad that shows one
// frame, or two frames side by side (any two pipelines, left and right) split at a divider, plus
// the overlay texture on top. Frames arrive as 8-bit sRGB bytes (the host-copy path).
#pragma once

#include <cstdint>
#include <vector>

namespace rt::view {

// Loads the GL entry points through GLFW and compiles the shaders; needs a current context.
// Throws rt::Error naming what is missing.
class GlDisplay {
  public:
    GlDisplay();
    ~GlDisplay();
    GlDisplay(const GlDisplay&) = delete;
    GlDisplay& operator=(const GlDisplay&) = delete;

    // slot 0 = left (or the only) frame, slot 1 = right frame. Rows top first, 3 bytes per
    // pixel. The texture is reallocated only when the size changes.
    void uploadFrame(int slot, const std::vector<uint8_t>& rgb, int width, int height);
    // Overlay textures (text panels), slots 0..kOverlays-1. Rows top first, 4 bytes per pixel,
    // straight alpha.
    static constexpr int kOverlays = 3;
    void uploadOverlay(int slot, const std::vector<uint8_t>& rgba, int width, int height);

    // Draws every shader variant once, so that the driver's shader compiler (LLVM in Mesa's
    // llvmpipe) is done before the render thread's OpenCL compiler (LLVM in PoCL) starts.
    void warmUp();

    struct DrawParams {
        int fbWidth = 0, fbHeight = 0;
        bool split = false;
        float divider = 0.5f;     // fraction of the window width where the right frame starts
        bool showDivider = true;  // a thin line at the divider (hidden with the overlay)
        struct Placement {
            int slot;
            int x, y;   // window pixels from the top-left corner
            int scale;  // integer magnification of the overlay texels
        };
        std::vector<Placement> overlays;
    };
    void draw(const DrawParams& p);

    // The back buffer as rows top first, 3 bytes per pixel (what the window shows).
    std::vector<uint8_t> readPixels(int fbWidth, int fbHeight);

  private:
    struct Texture {
        unsigned id = 0;
        int width = 0, height = 0;
    };
    void upload(Texture& t, const void* data, int width, int height, bool rgba);

    unsigned vao_ = 0, frameProgram_ = 0, overlayProgram_ = 0;
    Texture frames_[2], overlays_[kOverlays];
};

}  // namespace rt::view
