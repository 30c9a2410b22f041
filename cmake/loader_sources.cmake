# The host sources that load a scene and build its acceleration structure. They need neither
# OpenCL nor OpenImageIO, so the libFuzzer targets (tests/fuzz) compile them alone; rtlab_core
# compiles the same list. One list, so that a new structure cannot reach one build and not the
# other. Paths are relative to the repository root: prepend it where the list is used.
set(RTLAB_LOADER_SOURCES
    core/scene.cpp core/scene_loader.cpp core/obj_loader.cpp
    core/accel.cpp core/accel_bvh.cpp core/accel_grid.cpp core/accel_wide.cpp
    core/accel_cwbvh.cpp)
