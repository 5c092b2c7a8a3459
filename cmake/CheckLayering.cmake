# The layering rules (docs/ARCHITECTURE.md §2), checked at three levels:
#   - top-level folders: each library includes only the folders it links (core <- method <-
#     baselines; core <- datagen, calibration; benchmark uses all of those; cli uses everything);
#   - core/'s concerns: util <- files <- image <- geometry <- dataset <- radiometry, metrics;
#   - method/'s pipeline stages: gaussian, tonemap <- raster <- render; gaussian, tonemap <- optim;
#     render, optim <- train <- run.
# A file may include its own folder and the folders listed for it. Tests (*_test.cpp, and the
# test-only helpers named *_test_util.* or *for_test.h) are exempt: they may read results back
# through later stages. Used at configure time (hdr4d_check_layering) and as a script by the tests:
#   cmake -DROOT=<repository root> -P cmake/CheckLayering.cmake

cmake_policy(SET CMP0057 NEW)  # if(IN_LIST) in script mode

# Level "top": folders of the repository root. viz is core's picture library, so it is core.
set(_HDR4D_LEVEL_top_PREFIX "")
set(_HDR4D_LEVEL_top_FOLDERS core method baselines datagen calibration benchmark cli)
set(_HDR4D_ALLOWED_top_core "")
set(_HDR4D_ALLOWED_top_method "core")
set(_HDR4D_ALLOWED_top_baselines "core;method")
set(_HDR4D_ALLOWED_top_datagen "core")
set(_HDR4D_ALLOWED_top_calibration "core")
set(_HDR4D_ALLOWED_top_benchmark "core;method;baselines;datagen;calibration")
set(_HDR4D_ALLOWED_top_cli "core;method;baselines;datagen;calibration;benchmark")

# Level "core": core/'s sub-folders, mirroring their target_link_libraries.
set(_HDR4D_LEVEL_core_PREFIX "core/")
set(_HDR4D_LEVEL_core_FOLDERS util files image geometry dataset radiometry metrics viz)
set(_HDR4D_ALLOWED_core_util "")
set(_HDR4D_ALLOWED_core_files "util")
set(_HDR4D_ALLOWED_core_image "util;files")
set(_HDR4D_ALLOWED_core_geometry "util;files;image")
set(_HDR4D_ALLOWED_core_dataset "util;files;image;geometry")
set(_HDR4D_ALLOWED_core_radiometry "util;files;image;geometry;dataset")
set(_HDR4D_ALLOWED_core_metrics "util;files;image;geometry;dataset")
set(_HDR4D_ALLOWED_core_viz "util;files;image;geometry;dataset;radiometry;metrics")

# Level "method": the pipeline stages, mirroring their target_link_libraries.
set(_HDR4D_LEVEL_method_PREFIX "method/")
set(_HDR4D_LEVEL_method_FOLDERS gaussian tonemap raster render optim train run)
set(_HDR4D_ALLOWED_method_gaussian "")
set(_HDR4D_ALLOWED_method_tonemap "")
set(_HDR4D_ALLOWED_method_raster "gaussian")
set(_HDR4D_ALLOWED_method_render "gaussian;raster;tonemap")
set(_HDR4D_ALLOWED_method_optim "gaussian;tonemap")
set(_HDR4D_ALLOWED_method_train "gaussian;raster;tonemap;render;optim")
set(_HDR4D_ALLOWED_method_run "gaussian;raster;tonemap;render;optim;train")

# Appends to `out` the "file includes x" violations of one level under `root` (the repository
# root, or a test tree laid out like it).
function(_hdr4d_level_violations root level out)
  set(found "${${out}}")
  set(prefix "${_HDR4D_LEVEL_${level}_PREFIX}")
  set(base "${root}/${prefix}")
  if(NOT IS_DIRECTORY "${base}")
    set(${out} "${found}" PARENT_SCOPE)
    return()
  endif()
  if(prefix)  # a level below the root: nothing may sit loose beside its folders
    file(GLOB loose RELATIVE "${root}" "${base}*.h" "${base}*.cpp")
    foreach(f IN LISTS loose)
      list(APPEND found "${f} is loose in ${prefix} (it belongs to a sub-folder)")
    endforeach()
  endif()
  set(folders ${_HDR4D_LEVEL_${level}_FOLDERS})
  list(JOIN folders "|" alternatives)
  foreach(folder IN LISTS folders)
    file(GLOB_RECURSE files RELATIVE "${root}" "${base}${folder}/*.h" "${base}${folder}/*.cpp")
    set(allowed ${folder} ${_HDR4D_ALLOWED_${level}_${folder}})
    foreach(f IN LISTS files)
      if(f MATCHES "(_test\\.cpp|_test_util\\.(h|cpp)|for_test\\.h)$")
        continue()
      endif()
      file(STRINGS "${root}/${f}" includes REGEX "^#include \"${prefix}(${alternatives})/")
      foreach(line IN LISTS includes)
        string(REGEX MATCH "\"${prefix}([a-z_0-9]+)/[^\"]+\"" m "${line}")
        if(NOT CMAKE_MATCH_1 IN_LIST allowed)
          string(REPLACE "\"" "" m "${m}")
          list(APPEND found "${f} includes ${m}")
        endif()
      endforeach()
    endforeach()
  endforeach()
  set(${out} "${found}" PARENT_SCOPE)
endfunction()

function(hdr4d_check_layering root)
  set(bad "")
  foreach(level top core method)
    _hdr4d_level_violations("${root}" ${level} bad)
  endforeach()
  if(bad)
    list(JOIN bad "\n  " text)
    message(FATAL_ERROR "layering broken (a folder may include only the folders it links; see "
                        "docs/ARCHITECTURE.md §2):\n  ${text}")
  endif()
endfunction()

if(CMAKE_SCRIPT_MODE_FILE AND ROOT)
  get_filename_component(_dir "${ROOT}" ABSOLUTE)
  hdr4d_check_layering("${_dir}")
  message(STATUS "layering holds")
endif()
