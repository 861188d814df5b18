# Checks that every #include "..." in the library follows the layer order:
#
#   data -> physics -> io, tables -> gpu -> post          reference -> physics
#   astronomy -> physics
#   planet -> the public headers of post and below, and data (its GLSL text)
#
# (an arrow points from a layer to one that may use it; see docs/architecture.md).
# A file of a layer may include its own layer's files and those of the layers it
# depends on, nothing above. Run at build time by src/CMakeLists.txt, so a
# back-edge is a build error:
#   cmake -DROOT=<source dir> -DSTAMP=<file written on success> -P check_layers.cmake

# Which layer a path (relative to ROOT) belongs to. Public headers are listed
# one by one: they all live in include/atmos/.
function(layer_of path out)
  set(layer "")
  if(path MATCHES "^src/data/")
    set(layer data)
  elseif(path MATCHES "^src/physics/" OR path MATCHES "^include/atmos/(atmosphere|colour|eclipse|table_sizes|water)\\.hpp$")
    set(layer physics)
  elseif(path MATCHES "^src/astronomy/" OR path MATCHES "^include/atmos/(ephemeris|star_catalogue)\\.hpp$")
    set(layer astronomy)
  elseif(path MATCHES "^src/io/" OR path MATCHES "^include/atmos/(image|planet_file|planet_parameters)\\.hpp$")
    set(layer io)
  elseif(path MATCHES "^src/(precompute|runtime)/" OR path MATCHES "^include/atmos/(tables|sky)\\.hpp$")
    set(layer tables)
  elseif(path MATCHES "^src/gpu/" OR path MATCHES "^include/atmos/(renderer|plugin|stereo)\\.hpp$")
    set(layer gpu)
  elseif(path MATCHES "^src/post/" OR path MATCHES "^include/atmos/post\\.hpp$")
    set(layer post)
  elseif(path MATCHES "^src/reference/")
    set(layer reference)
  elseif(path MATCHES "^src/planet/" OR path MATCHES "^include/atmos/(globe|ocean)\\.hpp$")
    set(layer planet)
  endif()
  set(${out} "${layer}" PARENT_SCOPE)
endfunction()

# The layers each layer may use (besides itself).
set(uses_data "")
set(uses_physics data)
set(uses_io physics data)
set(uses_tables physics data)
set(uses_gpu tables io physics data)
set(uses_post gpu tables io physics data)
set(uses_reference physics)
set(uses_astronomy physics data)
# The globe uses the library as an engine does: public headers only (checked
# below), and the data layer's embedded GLSL text.
set(uses_planet post gpu tables io physics data)

file(GLOB_RECURSE files RELATIVE ${ROOT}
  ${ROOT}/src/*.cpp ${ROOT}/src/*.hpp ${ROOT}/src/*.glsl ${ROOT}/include/atmos/*.hpp)
set(errors "")
foreach(file IN LISTS files)
  layer_of(${file} layer)
  if(layer STREQUAL "")
    string(APPEND errors "  ${file}: not in any layer (add it to cmake/check_layers.cmake)\n")
    continue()
  endif()
  file(STRINGS ${ROOT}/${file} includes REGEX "^[ \t]*#[ \t]*include[ \t]*\"[^\"]+\"")
  foreach(line IN LISTS includes)
    string(REGEX REPLACE "^[ \t]*#[ \t]*include[ \t]*\"([^\"]+)\".*" "\\1" target "${line}")
    if(EXISTS ${ROOT}/src/${target})
      set(target_path src/${target})
    elseif(EXISTS ${ROOT}/include/${target})
      set(target_path include/${target})
    else()
      # Generated files and headers next to the including file.
      get_filename_component(dir ${file} DIRECTORY)
      if(EXISTS ${ROOT}/${dir}/${target})
        set(target_path ${dir}/${target})
      else()
        continue()
      endif()
    endif()
    layer_of(${target_path} used)
    if(used STREQUAL "" OR used STREQUAL layer)
      continue()
    endif()
    if(layer STREQUAL "planet" AND target_path MATCHES "^src/" AND NOT target_path MATCHES "^src/data/")
      string(APPEND errors "  ${file} (layer planet) includes ${target_path}: the globe uses only public headers\n")
      continue()
    endif()
    list(FIND uses_${layer} ${used} allowed)
    if(allowed EQUAL -1)
      string(APPEND errors "  ${file} (layer ${layer}) includes ${target_path} (layer ${used})\n")
    endif()
  endforeach()
endforeach()

if(NOT errors STREQUAL "")
  message(FATAL_ERROR "atmos layering: includes against the layer order "
                      "(cmake/check_layers.cmake, docs/architecture.md):\n${errors}")
endif()
if(DEFINED STAMP)
  file(WRITE ${STAMP} "layers checked\n")
endif()
