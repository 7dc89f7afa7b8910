# SEGSLAM_SANITIZE=ON builds everything with AddressSanitizer (LeakSanitizer included) and
# UndefinedBehaviorSanitizer; any undefined behaviour aborts the process, so a test that
# runs into one fails. See docs/testing.md for how CI runs it and how to run it locally.
option(SEGSLAM_SANITIZE "Build with -fsanitize=address,undefined (UBSan fatal)" OFF)

if(SEGSLAM_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer
                      -fno-sanitize-recover=undefined)
  add_link_options(-fsanitize=address,undefined)
endif()

# segslam_sanitizer_defaults(): links cmake/sanitizers/sanitizer_options.cpp into every
# executable defined so far (tests, the CLI, benchmarks), so that the run-time options and
# the LeakSanitizer suppressions of third-party libraries apply however a binary is run
# (ctest, gtest discovery at build time, the CLI started by a test, a developer's shell).
# Environment variables (ASAN_OPTIONS, LSAN_OPTIONS, UBSAN_OPTIONS) still override them.
function(_segslam_collect_executables DIR OUT)
  get_property(targets DIRECTORY ${DIR} PROPERTY BUILDSYSTEM_TARGETS)
  set(found)
  foreach(t IN LISTS targets)
    get_target_property(type ${t} TYPE)
    if(type STREQUAL "EXECUTABLE")
      list(APPEND found ${t})
    endif()
  endforeach()
  get_property(subdirs DIRECTORY ${DIR} PROPERTY SUBDIRECTORIES)
  foreach(sub IN LISTS subdirs)
    _segslam_collect_executables(${sub} sub_found)
    list(APPEND found ${sub_found})
  endforeach()
  set(${OUT} ${found} PARENT_SCOPE)
endfunction()

function(segslam_sanitizer_defaults)
  if(NOT SEGSLAM_SANITIZE)
    return()
  endif()
  add_library(segslam_sanitizer_options OBJECT
    ${PROJECT_SOURCE_DIR}/cmake/sanitizers/sanitizer_options.cpp)
  target_compile_definitions(segslam_sanitizer_options PRIVATE
    SEGSLAM_LSAN_SUPPRESSIONS="${PROJECT_SOURCE_DIR}/cmake/sanitizers/lsan.supp")
  # The canary (tests/sanitizers/): each sanitizer must catch its planted error.
  add_executable(sanitizer_canary ${PROJECT_SOURCE_DIR}/tests/sanitizers/sanitizer_canary.cpp)
  _segslam_collect_executables(${PROJECT_SOURCE_DIR} executables)
  foreach(exe IN LISTS executables)
    target_sources(${exe} PRIVATE $<TARGET_OBJECTS:segslam_sanitizer_options>)
  endforeach()
  if(SEGSLAM_BUILD_TESTS)
    add_test(NAME sanitizer_catches_heap_overflow COMMAND sanitizer_canary heap-overflow)
    add_test(NAME sanitizer_ub_is_fatal COMMAND sanitizer_canary signed-overflow)
    add_test(NAME sanitizer_catches_our_leaks COMMAND sanitizer_canary leak)
    set_tests_properties(sanitizer_catches_heap_overflow PROPERTIES
      PASS_REGULAR_EXPRESSION "AddressSanitizer: heap-buffer-overflow")
    set_tests_properties(sanitizer_ub_is_fatal PROPERTIES
      PASS_REGULAR_EXPRESSION "runtime error: signed integer overflow"
      FAIL_REGULAR_EXPRESSION "UBSAN-NOT-FATAL")
    set_tests_properties(sanitizer_catches_our_leaks PROPERTIES
      PASS_REGULAR_EXPRESSION "LeakSanitizer: detected memory leaks")
    set_tests_properties(sanitizer_catches_heap_overflow sanitizer_ub_is_fatal
      sanitizer_catches_our_leaks PROPERTIES LABELS sanitizer TIMEOUT 60)
  endif()
endfunction()

# SEGSLAM_BUILD_FUZZERS=ON (with clang) builds libFuzzer targets of the file readers
# (tests/fuzz/) instead of the normal tree: only the libraries they need (core, scenes,
# seg, slam), all instrumented for coverage, AddressSanitizer and UBSan.
option(SEGSLAM_BUILD_FUZZERS "Build the libFuzzer targets of tests/fuzz (clang only)" OFF)

if(SEGSLAM_BUILD_FUZZERS)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "SEGSLAM_BUILD_FUZZERS needs clang (libFuzzer), e.g. "
                        "CXX=clang++-14 cmake -S . -B build-fuzz -DSEGSLAM_BUILD_FUZZERS=ON")
  endif()
  if(SEGSLAM_SANITIZE)
    message(FATAL_ERROR "SEGSLAM_BUILD_FUZZERS already builds with the sanitizers; "
                        "leave SEGSLAM_SANITIZE off")
  endif()
  add_compile_options(-fsanitize=fuzzer-no-link,address,undefined -fno-omit-frame-pointer
                      -fno-sanitize-recover=undefined)
  add_link_options(-fsanitize=address,undefined)
endif()
