// rtlab — the persistent schedules' phase clocks (handout.cl, RT_PERSIST_PHASE_CLOCKS; NVIDIA, the
// counting frame): which of core/types.h's RT_PHASES clock slots counts which phase of a step, and
// the names the rows' extras give them (phase_mcycles_<name>). Plain macros, valid C++ and
// OpenCL C alike.
#ifndef RTLAB_PERSIST_PHASES_H
#define RTLAB_PERSIST_PHASES_H

#define RT_PHASE_BOOKKEEPING 0  // pixels, stacks and results; the bounce loop's batches and sums
#define RT_PHASE_TRACE 1        // the warp's rays, and their shadow rays but in a shadow pass
#define RT_PHASE_TRACE_WAIT 2   // at the barrier after the trace, for the group's slowest warp
#define RT_PHASE_FILE 3         // filing the hits: in key order; the bounce loop's staged hits
#define RT_PHASE_SHADE 4        // shading the hits
#define RT_PHASE_SHADE_WAIT 5   // at the barrier after the shading
#define RT_PHASE_SHADOW 6       // the staged bounce loop's shadow pass
#define RT_PHASE_SHADOW_WAIT 7  // at the barrier after it
#define RT_PHASE_NAMES \
    { "bookkeeping", "trace", "trace_wait", "file", "shade", "shade_wait", "shadow", "shadow_wait" }

#endif
