# The host sources that load a scene and build its acceleration structure. They need neither
# OpenCL nor OpenImageIO, so the libFuzzer targets (tests/fuzz) compile them alone; rtlab_core
# compiles the same list. One list, so that a new structure cannot reach one build and not the
# other. Paths are relative to the repository root: prepend it where the list is used.
set(RTLAB_LOADER_SOURCES
    core/scene.cpp core/scene_loader.cpp core/nff_loader.cpp core/obj_loader.cpp core/model_loader.cpp
    core/accel.cpp core/accel_bvh.cpp core/accel_grid.cpp core/accel_wide.cpp
    core/accel_cwbvh.cpp)

# Every acceleration structure the loaders can select must be in the list; fail at configure time
# rather than at the fuzz targets' link, which only CI's stability step reaches.
get_filename_component(_rtlab_root ${CMAKE_CURRENT_LIST_DIR}/.. ABSOLUTE)
file(GLOB _rtlab_accel_sources RELATIVE ${_rtlab_root} ${_rtlab_root}/core/accel*.cpp)
foreach(_source IN LISTS _rtlab_accel_sources)
    if(NOT _source IN_LIST RTLAB_LOADER_SOURCES)
        message(FATAL_ERROR "cmake/loader_sources.cmake: ${_source} is missing from RTLAB_LOADER_SOURCES")
    endif()
endforeach()
