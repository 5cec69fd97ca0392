# Build-time RGB-to-spectrum tables (Jakob and Hanika 2019) for pbrt-v4's named colour
# spaces. The host tool rgb2spec_opt (src/tools/rgb2spec_opt.cpp) computes each table into
# ${CMAKE_BINARY_DIR}/rgbspectrum_<space>.cpp, which joins the library's sources through
# PBRT_GENERATED_SOURCES. The tool uses the library's own colorimetry (CIE data, spectra,
# colour spaces), so the tables fit the spectra the renderer evaluates. It runs once per
# clean build (a few to ~10 s of CPU per colour space; threads inside the tool).

set(_rgb2spec_src ${CMAKE_CURRENT_LIST_DIR}/../src)
add_executable(rgb2spec_opt
  ${_rgb2spec_src}/tools/rgb2spec_opt.cpp
  ${_rgb2spec_src}/pbrt/pbrt.cpp
  ${_rgb2spec_src}/pbrt/util/cie_data.cpp
  ${_rgb2spec_src}/pbrt/util/spectrum.cpp
  ${_rgb2spec_src}/pbrt/util/file.cpp
  ${_rgb2spec_src}/pbrt/util/color.cpp)
target_include_directories(rgb2spec_opt PRIVATE ${_rgb2spec_src})
target_link_libraries(rgb2spec_opt PRIVATE Threads::Threads)
# Optimized even in Debug builds: the tool's run time is part of every clean build.
# -fno-math-errno lets the compiler vectorize the sqrt in the inner loop (5x faster); it
# changes no result.
target_compile_options(rgb2spec_opt PRIVATE -O3 -fno-math-errno)

#
# A second build directory (the sanitizer and fuzzing build, scripts/fuzz.sh) can take the
# tables of a first one instead of computing them again: -DPBRT_RGB2SPEC_FROM=<that
# build directory> copies its rgbspectrum_<space>.cpp.
set(PBRT_RGB2SPEC_FROM "" CACHE PATH "Build directory whose RGB-to-spectrum tables to copy instead of computing them")
foreach(_space srgb dci-p3 rec2020 aces2065-1)
  set(_out ${CMAKE_BINARY_DIR}/rgbspectrum_${_space}.cpp)
  set(_from ${PBRT_RGB2SPEC_FROM}/rgbspectrum_${_space}.cpp)
  if(PBRT_RGB2SPEC_FROM AND EXISTS ${_from})
    add_custom_command(
      OUTPUT ${_out}
      COMMAND ${CMAKE_COMMAND} -E copy ${_from} ${_out}
      DEPENDS ${_from}
      COMMENT "Copying the RGB-to-spectrum table for ${_space} from ${PBRT_RGB2SPEC_FROM}"
      VERBATIM)
  else()
    add_custom_command(
      OUTPUT ${_out}
      COMMAND rgb2spec_opt ${_space} ${_out}
      DEPENDS rgb2spec_opt
      COMMENT "Computing the RGB-to-spectrum table for ${_space}"
      VERBATIM)
  endif()
  list(APPEND PBRT_GENERATED_SOURCES ${_out})
endforeach()
