# gust_embed_shaders(TARGET <name> SOURCES <files...> [DEPENDS <files...>] [INCLUDES <dirs...>] [TEST_ONLY]
#                    [VARIANT <suffix> <DEFINE> VARIANT_SOURCES <files...>]
#                    [VARIANT_OF <file> <suffix> <DEFINE>...])
# Compiles each GLSL file to SPIR-V with glslangValidator at build time and emits a header
# <binary>/gust_shaders/<stem>_<stage>.h holding `const uint32_t <stem>_<stage>[]`, so the library
# ships no loose shader files. Each of VARIANT_SOURCES (also listed in SOURCES) is compiled a second time
# with -D<DEFINE> into <stem>_<suffix>_<stage>.h; VARIANT_OF does the same for one file with its own suffix
# and define (each triple). The target becomes an INTERFACE library carrying the include path (build
# tree only); it is listed in the global property GUST_SHADER_TARGETS so that cmake/GustInstall.cmake can
# export it beside the static libraries that name it as a private dependency (unless TEST_ONLY: a test's
# shaders). INCLUDES adds directories #include searches after the source's own.
function(gust_embed_shaders)
  cmake_parse_arguments(ARG "TEST_ONLY" "TARGET" "SOURCES;DEPENDS;VARIANT;VARIANT_SOURCES;VARIANT_OF;INCLUDES" ${ARGN})
  set(out_dir ${CMAKE_CURRENT_BINARY_DIR}/gust_shaders)
  file(MAKE_DIRECTORY ${out_dir})
  set(jobs)
  foreach(src IN LISTS ARG_SOURCES)
    list(APPEND jobs "${src}||")
  endforeach()
  if(ARG_VARIANT)
    list(GET ARG_VARIANT 0 suffix)
    list(GET ARG_VARIANT 1 define)
    foreach(src IN LISTS ARG_VARIANT_SOURCES)
      list(APPEND jobs "${src}|_${suffix}|-D${define}")
    endforeach()
  endif()
  # VARIANT_OF: triples of source, suffix and define, for a variant that only one shader has.
  list(LENGTH ARG_VARIANT_OF variant_of_length)
  if(variant_of_length GREATER 0)
    math(EXPR last_triple "${variant_of_length} - 3")
    foreach(i RANGE 0 ${last_triple} 3)
      math(EXPR suffix_at "${i} + 1")
      math(EXPR define_at "${i} + 2")
      list(GET ARG_VARIANT_OF ${i} src)
      list(GET ARG_VARIANT_OF ${suffix_at} suffix)
      list(GET ARG_VARIANT_OF ${define_at} define)
      list(APPEND jobs "${src}|_${suffix}|-D${define}")
    endforeach()
  endif()
  set(include_flags)
  foreach(dir IN LISTS ARG_INCLUDES)
    list(APPEND include_flags -I${dir})
  endforeach()
  set(headers)
  foreach(job IN LISTS jobs)
    string(REPLACE "|" ";" parts "${job}")
    list(GET parts 0 src)
    list(GET parts 1 suffix)
    list(GET parts 2 define)
    get_filename_component(stem ${src} NAME_WE)
    get_filename_component(ext ${src} LAST_EXT)
    string(SUBSTRING ${ext} 1 -1 stage)
    set(var ${stem}${suffix}_${stage})
    set(header ${out_dir}/${var}.h)
    add_custom_command(
      OUTPUT ${header}
      COMMAND ${GLSLANG_VALIDATOR} -V --target-env vulkan1.2 ${define} -I${CMAKE_CURRENT_SOURCE_DIR} ${include_flags}
              --vn ${var} -o ${header} ${CMAKE_CURRENT_SOURCE_DIR}/${src}
      DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/${src} ${ARG_DEPENDS}
      COMMENT "glslang ${src} ${define}"
      VERBATIM)
    list(APPEND headers ${header})
  endforeach()
  add_custom_target(${ARG_TARGET}_spirv DEPENDS ${headers})
  add_library(${ARG_TARGET} INTERFACE)
  add_dependencies(${ARG_TARGET} ${ARG_TARGET}_spirv)
  target_include_directories(${ARG_TARGET} INTERFACE
    $<BUILD_INTERFACE:${CMAKE_CURRENT_BINARY_DIR}> $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}>)
  if(NOT ARG_TEST_ONLY)
    set_property(GLOBAL APPEND PROPERTY GUST_SHADER_TARGETS ${ARG_TARGET})
  endif()
endfunction()
