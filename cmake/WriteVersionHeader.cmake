# Run at build time (cmake -P), not at configure time, so that reports and dataset cache
# keys name the code that was actually built: writes OUTPUT with SEGSLAM_VERSION set to
# `git describe --always --dirty --tags` of SOURCE_DIR ("unknown" outside a git checkout),
# and leaves the file untouched when the version has not changed (no needless rebuilds).
execute_process(COMMAND git describe --always --dirty --tags
                WORKING_DIRECTORY ${SOURCE_DIR}
                OUTPUT_VARIABLE version OUTPUT_STRIP_TRAILING_WHITESPACE
                ERROR_QUIET)
if(NOT version)
  set(version "unknown")
endif()
set(content "// Written by cmake/WriteVersionHeader.cmake at build time; do not edit.\n#pragma once\n#define SEGSLAM_VERSION \"${version}\"\n")
set(old "")
if(EXISTS ${OUTPUT})
  file(READ ${OUTPUT} old)
endif()
if(NOT old STREQUAL content)
  file(WRITE ${OUTPUT} "${content}")
endif()
