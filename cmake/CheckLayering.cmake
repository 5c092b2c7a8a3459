# The layering rule of method/ (docs/ARCHITECTURE.md): a file in a stage folder may include
# "method/<stage>/..." only for its own stage and the stages it links. Tests (*_test.cpp) are
# exempt: they may read results back through later stages. Used at configure time
# (hdr4d_check_method_layering) and as a script by the tests:
#   cmake -DMETHOD_DIR=<dir> -DSTAGES="gaussian;tonemap;..." -P cmake/CheckLayering.cmake

cmake_policy(SET CMP0057 NEW)  # if(IN_LIST) in script mode

# What each stage may include besides itself; it mirrors the target_link_libraries of the stages.
set(_HDR4D_ALLOWED_gaussian "")
set(_HDR4D_ALLOWED_tonemap "")
set(_HDR4D_ALLOWED_raster "gaussian")
set(_HDR4D_ALLOWED_render "gaussian;raster;tonemap")
set(_HDR4D_ALLOWED_optim "gaussian;raster;tonemap;render")
set(_HDR4D_ALLOWED_train "gaussian;raster;tonemap;render;optim")
set(_HDR4D_ALLOWED_run "gaussian;raster;tonemap;render;optim;train")

# Sets `out` to a list of "file includes method/x/y" violations under method_dir.
function(_hdr4d_layering_violations method_dir stages out)
  set(found "")
  file(GLOB loose RELATIVE "${method_dir}" "${method_dir}/*.h" "${method_dir}/*.cpp")
  foreach(f IN LISTS loose)
    list(APPEND found "${f} is loose in method/ (it belongs to a stage folder)")
  endforeach()
  foreach(stage IN LISTS stages)
    file(GLOB_RECURSE files RELATIVE "${method_dir}" "${method_dir}/${stage}/*.h"
         "${method_dir}/${stage}/*.cpp")
    set(allowed ${stage} ${_HDR4D_ALLOWED_${stage}})
    foreach(f IN LISTS files)
      if(f MATCHES "_test\\.cpp$")
        continue()
      endif()
      file(STRINGS "${method_dir}/${f}" includes REGEX "^#include \"method/")
      foreach(line IN LISTS includes)
        string(REGEX MATCH "\"method/([a-z_0-9]+)/[^\"]+\"" m "${line}")
        if(NOT m)
          string(REGEX MATCH "\"method/[^\"]+\"" m "${line}")
          list(APPEND found "${f} includes ${m} (not in a stage folder)")
          continue()
        endif()
        set(included_stage "${CMAKE_MATCH_1}")
        if(NOT included_stage IN_LIST allowed)
          string(REPLACE "\"" "" m "${m}")
          list(APPEND found "${f} includes ${m}")
        endif()
      endforeach()
    endforeach()
  endforeach()
  set(${out} "${found}" PARENT_SCOPE)
endfunction()

function(hdr4d_check_method_layering method_dir stages)
  _hdr4d_layering_violations("${method_dir}" "${stages}" bad)
  if(bad)
    list(JOIN bad "\n  " text)
    message(FATAL_ERROR "method/ layering broken (a stage may include only the stages it links; "
                        "see docs/ARCHITECTURE.md):\n  ${text}")
  endif()
endfunction()

if(CMAKE_SCRIPT_MODE_FILE AND METHOD_DIR)
  get_filename_component(_dir "${METHOD_DIR}" ABSOLUTE)
  hdr4d_check_method_layering("${_dir}" "${STAGES}")
  message(STATUS "method/ layering holds")
endif()
