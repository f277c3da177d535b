# pcisim_include_root(TARGET LAYER [SCOPE]): TARGET and whatever links it see LAYER's headers as
# "LAYER/...", and nothing else of the tree. Each layer gets a folder of its own in the build
# holding one link to its source folder, so a header of a layer the target does not link is not
# found: a wrong-way include does not compile (DESIGN.md's layers; tests/architecture lists them).
function(pcisim_include_root target layer)
  set(scope PUBLIC)
  if(ARGC GREATER 2)
    set(scope ${ARGV2})
  endif()
  set(root ${CMAKE_BINARY_DIR}/include/${layer})
  if(NOT EXISTS ${root}/${layer})
    file(MAKE_DIRECTORY ${root})
    file(CREATE_LINK ${CMAKE_SOURCE_DIR}/${layer} ${root}/${layer} SYMBOLIC)
  endif()
  target_include_directories(${target} ${scope} ${root})
endfunction()

# pcisim_filter_sources(LIST_VAR REGEX...): drops from LIST_VAR (absolute paths) every file whose
# path below the source tree, with a leading "/" ("/anatomy/case/case_folder.cc"), matches one of
# the regexes. Never the absolute path: a checkout under /home/x/case/ would match "/case/" in all.
function(pcisim_filter_sources list_var)
  set(kept)
  foreach(src IN LISTS ${list_var})
    file(RELATIVE_PATH rel ${CMAKE_SOURCE_DIR} ${src})
    set(drop FALSE)
    foreach(pattern IN LISTS ARGN)
      if("/${rel}" MATCHES "${pattern}")
        set(drop TRUE)
        break()
      endif()
    endforeach()
    if(NOT drop)
      list(APPEND kept ${src})
    endif()
  endforeach()
  set(${list_var} ${kept} PARENT_SCOPE)
endfunction()

# pcisim_library(NAME DIR [DEPS ...] [EXCLUDE REGEX...]): one static library from every .cc (and
# .cu when CUDA is on) below DIR but those EXCLUDE names (pcisim_filter_sources). Globbing keeps
# "one concept per file" cheap: add a file, re-run cmake.
function(pcisim_library name dir)
  cmake_parse_arguments(ARG "" "" "DEPS;EXCLUDE" ${ARGN})
  file(GLOB_RECURSE srcs CONFIGURE_DEPENDS ${dir}/*.cc)
  if(PCISIM_HAVE_CUDA)
    file(GLOB_RECURSE cu_srcs CONFIGURE_DEPENDS ${dir}/*.cu)
    list(APPEND srcs ${cu_srcs})
  endif()
  pcisim_filter_sources(srcs ${ARG_EXCLUDE})
  # the layer (DESIGN.md) is the top-level folder; tests/architecture checks its links
  file(RELATIVE_PATH rel ${CMAKE_SOURCE_DIR} ${dir})
  string(REGEX REPLACE "/.*" "" layer "${rel}")
  if(NOT srcs)
    # headers only so far
    add_library(${name} INTERFACE)
    target_link_libraries(${name} INTERFACE ${ARG_DEPS})
    pcisim_include_root(${name} ${layer} INTERFACE)
    set_target_properties(${name} PROPERTIES PCISIM_LAYER ${layer})
    return()
  endif()
  add_library(${name} STATIC ${srcs})
  target_link_libraries(${name} PUBLIC ${ARG_DEPS})
  set_target_properties(${name} PROPERTIES PCISIM_LAYER ${layer})
  pcisim_include_root(${name} ${layer})
  if(PCISIM_HAVE_CUDA)
    target_compile_definitions(${name} PUBLIC PCISIM_HAVE_CUDA=1)
    set_target_properties(${name} PROPERTIES CUDA_SEPARABLE_COMPILATION OFF POSITION_INDEPENDENT_CODE ON)
    target_compile_options(${name} PRIVATE $<$<COMPILE_LANGUAGE:CUDA>:-O3 -lineinfo --expt-relaxed-constexpr>)
  endif()
endfunction()

# pcisim_test(NAME DIR [SERIAL] DEPS...): one gtest executable from every *_test.cc below DIR;
# SERIAL runs its tests alone (timing-sensitive whole-server runs) and labels them "integration",
# the others "unit"; tests/heavy.txt adds "heavy" or "timing" to single tests (tests/test_labels.cmake)
function(pcisim_test name dir)
  cmake_parse_arguments(ARG "SERIAL" "" "" ${ARGN})
  file(GLOB_RECURSE srcs CONFIGURE_DEPENDS ${dir}/*_test.cc)
  if(NOT srcs)
    return()
  endif()
  add_executable(${name} ${srcs})
  target_link_libraries(${name} PRIVATE ${ARG_UNPARSED_ARGUMENTS} GTest::gtest GTest::gtest_main)
  pcisim_include_root(${name} tests PRIVATE)  # helpers as "tests/common/..."
  target_compile_definitions(${name} PRIVATE PCISIM_SOURCE_DIR="${CMAKE_SOURCE_DIR}" PCISIM_BINARY_DIR="${CMAKE_BINARY_DIR}")
  set(label unit)
  if(ARG_SERIAL)
    set(label integration)
  endif()
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60 PROPERTIES TIMEOUT 300 RUN_SERIAL ${ARG_SERIAL} LABELS ${label})
  set_property(GLOBAL APPEND PROPERTY PCISIM_TEST_TARGETS "${name}:${label}")
endfunction()
