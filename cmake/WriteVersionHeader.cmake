# Run at build time (cmake -P), not at configure time, so that reports and dataset cache
# keys name the code that was actually built: writes OUTPUT with SEGSLAM_VERSION set to
# `git describe --always --dirty --tags` of SOURCE_DIR ("unknown" outside a git checkout),
# and leaves the file untouched when the version has not changed (no needless rebuilds).
# A dirty tree's version also carries a hash of its changes (the diff against HEAD and
# the untracked files' names and contents): every uncommitted state would otherwise
# read "-dirty" alike, and a dataset cached under one would be taken for another's.
execute_process(COMMAND git describe --always --dirty --tags
                WORKING_DIRECTORY ${SOURCE_DIR}
                OUTPUT_VARIABLE version OUTPUT_STRIP_TRAILING_WHITESPACE
                ERROR_QUIET)
if(NOT version)
  set(version "unknown")
elseif(version MATCHES "-dirty$")
  execute_process(COMMAND git diff HEAD --binary
                  WORKING_DIRECTORY ${SOURCE_DIR}
                  OUTPUT_VARIABLE changes ERROR_QUIET)
  # Untracked sources only: editor and tool files outside .gitignore change no build.
  execute_process(COMMAND git -c core.quotePath=false ls-files --others --exclude-standard --
                          *.cpp *.h *.cmake CMakeLists.txt */CMakeLists.txt *.yaml *.sh
                  WORKING_DIRECTORY ${SOURCE_DIR}
                  OUTPUT_VARIABLE untracked OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
  if(untracked)
    string(REPLACE "\n" ";" untracked "${untracked}")
    foreach(file IN LISTS untracked)
      if(EXISTS "${SOURCE_DIR}/${file}" AND NOT IS_DIRECTORY "${SOURCE_DIR}/${file}")
        file(SHA256 "${SOURCE_DIR}/${file}" file_hash)
        string(APPEND changes "\n${file} ${file_hash}")
      endif()
    endforeach()
  endif()
  string(SHA256 changes_hash "${changes}")
  string(SUBSTRING "${changes_hash}" 0 8 changes_hash)
  set(version "${version}-${changes_hash}")
endif()
set(content "// Written by cmake/WriteVersionHeader.cmake at build time; do not edit.\n#pragma once\n#define SEGSLAM_VERSION \"${version}\"\n")
set(old "")
if(EXISTS ${OUTPUT})
  file(READ ${OUTPUT} old)
endif()
if(NOT old STREQUAL content)
  file(WRITE ${OUTPUT} "${content}")
endif()
