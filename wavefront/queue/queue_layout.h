// rtlab — the queue wavefront's shading classes, its shade queues (--queue-shade) and the layout
// of its counter buffer, shared by the host (wavefront/queue/*.cpp) and the kernels (queue.cl):
// plain #defines, valid C++ and OpenCL C alike, so both sides index the same words and classify
// materials alike.
#ifndef RTLAB_QUEUE_LAYOUT_H
#define RTLAB_QUEUE_LAYOUT_H

// Shading classes: one queue and one shade kernel each (--queue-shade class, the default), so
// that a launch runs one code path. The per-bounce histogram counts rays by class in every mode.
#define RT_Q_MISS 0        // escaped: environment only
#define RT_Q_DIFFUSE 1     // opaque, reflectance 0: local Blinn-Phong term, no child
#define RT_Q_MIRROR 2      // opaque, reflectance > 0: local term and a reflection child
#define RT_Q_GLASS 3       // opacity < 1: Fresnel, reflection and refraction children
#define RT_Q_PROCEDURAL 4  // like diffuse, with a procedural pattern: the costly one
#define RT_Q_CLASSES 5
// The class of a surface's material (a Material, core/types.h): the kernels sort hits by it and
// the host launches only the shade kernels of the classes a scene's materials have.
#define RT_Q_MATERIAL_CLASS(m)                          \
    ((m).opacity < 1.0f               ? RT_Q_GLASS      \
     : (m).reflectance > 0.0f         ? RT_Q_MIRROR     \
     : (m).pattern != RT_PATTERN_NONE ? RT_Q_PROCEDURAL \
                                      : RT_Q_DIFFUSE)

// Shade modes (--queue-shade): which queues extend puts the rays in, and so which rays share a
// shade launch (wavefront/queue/README.md, "Shade modes").
#define RT_Q_SHADE_CLASS 0    // one queue per class: the RT_Q_* above
#define RT_Q_SHADE_PATTERN 1  // the procedural class split into one queue per pattern
#define RT_Q_SHADE_SORT 2     // misses, and every hit in one queue sorted by material
// --queue-shade pattern: the queues of the classes before the procedural one, then one queue per
// pattern (RT_PATTERN_CHECKER..RT_PATTERN_BUMP, core/types.h) in place of the procedural queue.
#define RT_Q_PATTERNS 5
#define RT_Q_PATTERN_QUEUE(pattern) (RT_Q_PROCEDURAL - RT_PATTERN_CHECKER + (pattern))
// --queue-shade sort: the miss queue, every hit in extend's order, and the hits again in the
// order of their material ids (Queue_SortCount, Queue_SortBuckets, Queue_SortScatter).
#define RT_Q_HITS 1
#define RT_Q_SORTED 2  // as long as the hit queue: its length is RT_Q_HITS's word
// The most queues a mode has (pattern's), and so the queue lengths the counters hold.
#define RT_Q_QUEUES (RT_Q_PROCEDURAL + RT_Q_PATTERNS)

// Words of the counter buffer. The first RT_Q_PER_ITERATION are cleared before every extend.
#define RT_Q_COUNT 0                            // RT_Q_QUEUES shade-queue lengths
#define RT_Q_SHADOW (RT_Q_COUNT + RT_Q_QUEUES)  // hit rays queued for the shadow stage
#define RT_Q_CHILDREN (RT_Q_SHADOW + 1)         // children the shade stage spawned in all
#define RT_Q_CUT (RT_Q_CHILDREN + 1)            // rays before the first path cut for room
#define RT_Q_KEPT (RT_Q_CUT + 1)                // children of the rays before the cut
#define RT_Q_PER_ITERATION (RT_Q_KEPT + 1)
// --queue-launch device: the live rays of the bounce now enqueued (set by the host for a wave's
// camera rays, then by Queue_ScanSums for the next bounce; kept apart from the words cleared
// per bounce so that it survives into the next bounce), and a flag for a bounce whose children
// outgrew the pool (the host then renders the frame again with read-backs).
#define RT_Q_LIVE RT_Q_PER_ITERATION
#define RT_Q_OVERFLOW (RT_Q_LIVE + 1)
// Then, for the whole frame, rays per bounce (depth 0..16) and class: [depth * CLASSES + class].
#define RT_Q_HISTOGRAM (RT_Q_OVERFLOW + 1)
#define RT_Q_MAX_DEPTH 16
#define RT_Q_DEPTH_CLASSES ((RT_Q_MAX_DEPTH + 1) * RT_Q_CLASSES)
#define RT_Q_WORDS (RT_Q_HISTOGRAM + RT_Q_DEPTH_CLASSES)

// The local memory a work-group of the extend kernels declares (queue.cl, queue_packet.cl): the
// count and base of its pushes to each queue and to the shadow queue, and its histogram of depths
// and classes. The host checks --queue-local-pad against it.
#define RT_Q_PUSHES (RT_Q_QUEUES + 1)
#define RT_Q_EXTEND_LOCAL_INTS (2 * RT_Q_PUSHES + RT_Q_DEPTH_CLASSES)

#endif
