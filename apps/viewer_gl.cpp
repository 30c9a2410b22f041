// rtlab-view — OpenGL 3.3 core drawing: entry points loaded through GLFW (no loader library), one
// vertex shader that places a quad on a pixel rectangle, a frame shader that picks the left or
// right texture by window column, and an overlay shader with alpha blending.
#include "apps/viewer_gl.h"

#define GLFW_INCLUDE_NONE
#include <GL/glcorearb.h>
#include <GLFW/glfw3.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.h"

namespace rt::view {
namespace {

#define RT_GL_FUNCTIONS(X)                             \
    X(PFNGLGETSTRINGPROC, GetString)                   \
    X(PFNGLVIEWPORTPROC, Viewport)                     \
    X(PFNGLCLEARCOLORPROC, ClearColor)                 \
    X(PFNGLCLEARPROC, Clear)                           \
    X(PFNGLENABLEPROC, Enable)                         \
    X(PFNGLDISABLEPROC, Disable)                       \
    X(PFNGLFINISHPROC, Finish)                         \
    X(PFNGLBLENDFUNCPROC, BlendFunc)                   \
    X(PFNGLPIXELSTOREIPROC, PixelStorei)               \
    X(PFNGLREADBUFFERPROC, ReadBuffer)                 \
    X(PFNGLREADPIXELSPROC, ReadPixels)                 \
    X(PFNGLGENTEXTURESPROC, GenTextures)               \
    X(PFNGLDELETETEXTURESPROC, DeleteTextures)         \
    X(PFNGLBINDTEXTUREPROC, BindTexture)               \
    X(PFNGLACTIVETEXTUREPROC, ActiveTexture)           \
    X(PFNGLTEXIMAGE2DPROC, TexImage2D)                 \
    X(PFNGLTEXSUBIMAGE2DPROC, TexSubImage2D)           \
    X(PFNGLTEXPARAMETERIPROC, TexParameteri)           \
    X(PFNGLDRAWARRAYSPROC, DrawArrays)                 \
    X(PFNGLGENVERTEXARRAYSPROC, GenVertexArrays)       \
    X(PFNGLDELETEVERTEXARRAYSPROC, DeleteVertexArrays) \
    X(PFNGLBINDVERTEXARRAYPROC, BindVertexArray)       \
    X(PFNGLCREATESHADERPROC, CreateShader)             \
    X(PFNGLSHADERSOURCEPROC, ShaderSource)             \
    X(PFNGLCOMPILESHADERPROC, CompileShader)           \
    X(PFNGLGETSHADERIVPROC, GetShaderiv)               \
    X(PFNGLGETSHADERINFOLOGPROC, GetShaderInfoLog)     \
    X(PFNGLDELETESHADERPROC, DeleteShader)             \
    X(PFNGLCREATEPROGRAMPROC, CreateProgram)           \
    X(PFNGLATTACHSHADERPROC, AttachShader)             \
    X(PFNGLLINKPROGRAMPROC, LinkProgram)               \
    X(PFNGLGETPROGRAMIVPROC, GetProgramiv)             \
    X(PFNGLGETPROGRAMINFOLOGPROC, GetProgramInfoLog)   \
    X(PFNGLDELETEPROGRAMPROC, DeleteProgram)           \
    X(PFNGLUSEPROGRAMPROC, UseProgram)                 \
    X(PFNGLGETUNIFORMLOCATIONPROC, GetUniformLocation) \
    X(PFNGLUNIFORM1IPROC, Uniform1i)                   \
    X(PFNGLUNIFORM1FPROC, Uniform1f)                   \
    X(PFNGLUNIFORM4FPROC, Uniform4f)

namespace gl {
#define RT_GL_DECLARE(type, name) type name = nullptr;
RT_GL_FUNCTIONS(RT_GL_DECLARE)
#undef RT_GL_DECLARE
}  // namespace gl

void loadFunctions() {
    std::string missing;
#define RT_GL_LOAD(type, name)                                         \
    gl::name = reinterpret_cast<type>(glfwGetProcAddress("gl" #name)); \
    if (!gl::name) missing += std::string(missing.empty() ? "" : ", ") + "gl" #name;
    RT_GL_FUNCTIONS(RT_GL_LOAD)
#undef RT_GL_LOAD
    if (!missing.empty()) throw Error("the OpenGL driver lacks " + missing);
}

// A quad (triangle strip) on the pixel rectangle `rect` (x0, y0, x1, y1 in NDC); uv has y down
// so that texture rows are stored top first, as images are.
const char* kVertex = R"(#version 330 core
uniform vec4 rect;
out vec2 uv;
void main() {
    vec2 corner = vec2(gl_VertexID & 1, gl_VertexID >> 1);
    uv = vec2(corner.x, 1.0 - corner.y);
    gl_Position = vec4(mix(rect.xy, rect.zw, corner), 0.0, 1.0);
}
)";

// Columns left of `dividerPx` show the left frame, the rest the right frame (single view: both
// samplers are the same texture). Sampling is NEAREST, so at an integer scale every window pixel
// is exactly one frame pixel.
const char* kFrame = R"(#version 330 core
in vec2 uv;
uniform sampler2D leftFrame;
uniform sampler2D rightFrame;
uniform float dividerPx;
uniform int showDivider;
out vec4 color;
void main() {
    if (showDivider != 0 && abs(gl_FragCoord.x - dividerPx) < 1.0) {
        color = vec4(0.95, 0.85, 0.2, 1.0);
        return;
    }
    vec3 c = gl_FragCoord.x < dividerPx ? texture(leftFrame, uv).rgb : texture(rightFrame, uv).rgb;
    color = vec4(c, 1.0);
}
)";

const char* kOverlay = R"(#version 330 core
in vec2 uv;
uniform sampler2D overlay;
out vec4 color;
void main() { color = texture(overlay, uv); }
)";

unsigned compile(GLenum type, const char* source) {
    GLuint s = gl::CreateShader(type);
    gl::ShaderSource(s, 1, &source, nullptr);
    gl::CompileShader(s);
    GLint ok = 0;
    gl::GetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[1024] = {};
        gl::GetShaderInfoLog(s, sizeof log, nullptr, log);
        gl::DeleteShader(s);
        throw Error(std::string("compiling a viewer shader failed: ") + log);
    }
    return s;
}

unsigned link(const char* fragment) {
    GLuint vs = compile(GL_VERTEX_SHADER, kVertex), fs = compile(GL_FRAGMENT_SHADER, fragment);
    GLuint p = gl::CreateProgram();
    gl::AttachShader(p, vs);
    gl::AttachShader(p, fs);
    gl::LinkProgram(p);
    gl::DeleteShader(vs);
    gl::DeleteShader(fs);
    GLint ok = 0;
    gl::GetProgramiv(p, GL_LINK_STATUS, &ok);
    if (!ok) {
        char log[1024] = {};
        gl::GetProgramInfoLog(p, sizeof log, nullptr, log);
        gl::DeleteProgram(p);
        throw Error(std::string("linking a viewer shader failed: ") + log);
    }
    return p;
}

}  // namespace

GlDisplay::GlDisplay() {
    loadFunctions();
    frameProgram_ = link(kFrame);
    overlayProgram_ = link(kOverlay);
    gl::GenVertexArrays(1, &vao_);
    gl::UseProgram(frameProgram_);
    gl::Uniform1i(gl::GetUniformLocation(frameProgram_, "leftFrame"), 0);
    gl::Uniform1i(gl::GetUniformLocation(frameProgram_, "rightFrame"), 1);
    gl::UseProgram(overlayProgram_);
    gl::Uniform1i(gl::GetUniformLocation(overlayProgram_, "overlay"), 2);
}

GlDisplay::~GlDisplay() {
    for (Texture& t : frames_)
        if (t.id) gl::DeleteTextures(1, &t.id);
    for (Texture& t : overlays_)
        if (t.id) gl::DeleteTextures(1, &t.id);
    if (vao_) gl::DeleteVertexArrays(1, &vao_);
    if (frameProgram_) gl::DeleteProgram(frameProgram_);
    if (overlayProgram_) gl::DeleteProgram(overlayProgram_);
}

void GlDisplay::upload(Texture& t, const void* data, int width, int height, bool rgba) {
    GLenum format = rgba ? GL_RGBA : GL_RGB;
    if (!t.id) gl::GenTextures(1, &t.id);
    gl::BindTexture(GL_TEXTURE_2D, t.id);
    gl::PixelStorei(GL_UNPACK_ALIGNMENT, 1);
    if (t.width != width || t.height != height) {
        gl::TexImage2D(GL_TEXTURE_2D, 0, rgba ? GL_RGBA8 : GL_RGB8, width, height, 0, format,
                       GL_UNSIGNED_BYTE, data);
        gl::TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        gl::TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        gl::TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
        gl::TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
        t.width = width;
        t.height = height;
    } else {
        gl::TexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, width, height, format, GL_UNSIGNED_BYTE, data);
    }
}

void GlDisplay::uploadFrame(int slot, const std::vector<uint8_t>& rgb, int width, int height) {
    upload(frames_[slot & 1], rgb.data(), width, height, false);
}

void GlDisplay::uploadOverlay(int slot, const std::vector<uint8_t>& rgba, int width, int height) {
    if (slot >= 0 && slot < kOverlays) upload(overlays_[slot], rgba.data(), width, height, true);
}

void GlDisplay::warmUp() {
    // 1x1 black frames and a clear overlay: what the window shows until the first frame.
    std::vector<uint8_t> rgb(3, 0), rgba(4, 0);
    upload(frames_[0], rgb.data(), 1, 1, false);
    upload(frames_[1], rgb.data(), 1, 1, false);
    upload(overlays_[0], rgba.data(), 1, 1, true);
    DrawParams p;
    p.fbWidth = p.fbHeight = 4;
    p.split = true;
    p.overlays = {{0, 0, 0, 1}};
    draw(p);
    p.split = p.showDivider = false;
    draw(p);
    gl::Finish();
}

void GlDisplay::draw(const DrawParams& p) {
    gl::Viewport(0, 0, p.fbWidth, p.fbHeight);
    gl::ClearColor(0.1f, 0.1f, 0.1f, 1.f);
    gl::Clear(GL_COLOR_BUFFER_BIT);
    gl::BindVertexArray(vao_);
    if (frames_[0].id) {
        bool split = p.split && frames_[1].id;
        gl::UseProgram(frameProgram_);
        gl::ActiveTexture(GL_TEXTURE0);
        gl::BindTexture(GL_TEXTURE_2D, frames_[0].id);
        gl::ActiveTexture(GL_TEXTURE1);
        gl::BindTexture(GL_TEXTURE_2D, split ? frames_[1].id : frames_[0].id);
        float dividerPx = split ? std::round(p.divider * float(p.fbWidth)) : float(p.fbWidth);
        gl::Uniform1f(gl::GetUniformLocation(frameProgram_, "dividerPx"), dividerPx);
        gl::Uniform1i(gl::GetUniformLocation(frameProgram_, "showDivider"),
                      split && p.showDivider ? 1 : 0);
        gl::Uniform4f(gl::GetUniformLocation(frameProgram_, "rect"), -1.f, -1.f, 1.f, 1.f);
        gl::DrawArrays(GL_TRIANGLE_STRIP, 0, 4);
    }
    for (const DrawParams::Placement& o : p.overlays) {
        const Texture& t = overlays_[std::clamp(o.slot, 0, kOverlays - 1)];
        if (!t.id || p.fbWidth <= 0 || p.fbHeight <= 0) continue;
        // Whole overlay texels on whole window pixels, so the font stays crisp.
        float x0 = -1.f + 2.f * float(o.x) / float(p.fbWidth);
        float y1 = 1.f - 2.f * float(o.y) / float(p.fbHeight);
        float x1 = x0 + 2.f * float(t.width * o.scale) / float(p.fbWidth);
        float y0 = y1 - 2.f * float(t.height * o.scale) / float(p.fbHeight);
        gl::UseProgram(overlayProgram_);
        gl::ActiveTexture(GL_TEXTURE2);
        gl::BindTexture(GL_TEXTURE_2D, t.id);
        gl::Uniform4f(gl::GetUniformLocation(overlayProgram_, "rect"), x0, y0, x1, y1);
        gl::Enable(GL_BLEND);
        gl::BlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
        gl::DrawArrays(GL_TRIANGLE_STRIP, 0, 4);
        gl::Disable(GL_BLEND);
    }
    gl::ActiveTexture(GL_TEXTURE0);
}

std::vector<uint8_t> GlDisplay::readPixels(int fbWidth, int fbHeight) {
    std::vector<uint8_t> bottomUp(size_t(fbWidth) * fbHeight * 3);
    gl::PixelStorei(GL_PACK_ALIGNMENT, 1);
    gl::ReadBuffer(GL_BACK);
    gl::ReadPixels(0, 0, fbWidth, fbHeight, GL_RGB, GL_UNSIGNED_BYTE, bottomUp.data());
    std::vector<uint8_t> rows(bottomUp.size());
    size_t stride = size_t(fbWidth) * 3;
    for (int y = 0; y < fbHeight; ++y)
        std::copy_n(&bottomUp[size_t(fbHeight - 1 - y) * stride], stride,
                    &rows[size_t(y) * stride]);
    return rows;
}

}  // namespace rt::view
