// rtlab — how the persistent schedules hand work out, defined once for the kernels
// (persistent/handout.cl) and for the predictor that simulates them (auto/predict.cpp): the
// order pixels are taken in, and the keys hits are sorted by before shading.
//
// The order (Persistent_PixelOf, the predictor's stripPixel): whole rows go by bands of `th` rows,
// each band by strips of `tw` columns (the last band and the last strip of a band cut to fit), row
// by row inside a strip, so that a warp's 32 pixels are a tw x 32/tw block and its next ones lie
// below them. A plain macro, valid C++ and OpenCL C alike.
#ifndef RTLAB_HANDOUT_ORDER_H
#define RTLAB_HANDOUT_ORDER_H

#define RT_STRIP_MIN(a, b) ((a) < (b) ? (a) : (b))

// Pixel k of `rows` whole rows `width` wide: sets x (its column) and y (its row, from the first).
#define RT_STRIP_PIXEL(k, width, rows, tw, th, x, y)                                 \
    do {                                                                             \
        const int band_ = (int)((k) / ((width) * (th)));                             \
        const int bandRows_ = RT_STRIP_MIN((th), (rows)-band_ * (th));               \
        const int i_ = (int)((k)-band_ * (width) * (th));                            \
        const int strip_ = i_ / ((tw)*bandRows_), j_ = i_ - strip_ * (tw)*bandRows_; \
        const int stripWidth_ = RT_STRIP_MIN((tw), (width)-strip_ * (tw));           \
        (x) = strip_ * (tw) + j_ % stripWidth_;                                      \
        (y) = band_ * (th) + j_ / stripWidth_;                                       \
    } while (0)

// The keys (Regroup_KeyOf; the predictor's shadingKey): the code a lane runs to shade a hit, its
// procedural pattern (RT_PATTERN_NONE..BUMP, core/types.h), then these. The regrouped and staged
// bounce loops sort by pattern, a miss and (regrouped) an idle lane; the predictor counts the
// codes a warp step meets with a material without a pattern keyed by class too
// (RT_SHADING_CODE), since plain, mirror and glass hits run different code.
#define RT_KEY_MIRROR (RT_PATTERN_BUMP + 1)  // no pattern, reflective
#define RT_KEY_GLASS (RT_KEY_MIRROR + 1)     // no pattern, transparent
#define RT_KEY_MISS (RT_KEY_GLASS + 1)       // a ray that left the scene
#define RT_KEY_IDLE (RT_KEY_MISS + 1)        // a lane without a ray this step
#define RT_KEYS (RT_KEY_IDLE + 1)
// The code of a hit on material m (a Material).
#define RT_SHADING_CODE(m)                          \
    ((m).pattern != RT_PATTERN_NONE ? (m).pattern   \
     : (m).opacity < 1.0f           ? RT_KEY_GLASS  \
     : (m).reflectance > 0.0f       ? RT_KEY_MIRROR \
                                    : RT_PATTERN_NONE)

#endif
