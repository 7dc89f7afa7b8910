include(GNUInstallDirs)

# segslam_add_library(NAME [INSTALL] SRCS ... PUBLIC_LINK ... PRIVATE_LINK ...)
# One static library per top folder; include paths are rooted at the repository so
# headers are included as "core/camera.h". Linked as segslam::NAME, in this build and
# by another project through find_package(segslam). INSTALL puts the library and the
# folder's headers (all but *_internal.h) in `cmake --install`'s tree, in the export set
# segslamTargets (cmake/segslamConfig.cmake.in).
function(segslam_add_library NAME)
  cmake_parse_arguments(ARG "INSTALL" "" "SRCS;PUBLIC_LINK;PRIVATE_LINK" ${ARGN})
  add_library(segslam_${NAME} STATIC ${ARG_SRCS})
  add_library(segslam::${NAME} ALIAS segslam_${NAME})
  set_target_properties(segslam_${NAME} PROPERTIES EXPORT_NAME ${NAME})
  target_include_directories(segslam_${NAME} PUBLIC
    $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}/segslam>)
  target_link_libraries(segslam_${NAME} PUBLIC ${ARG_PUBLIC_LINK} PRIVATE ${ARG_PRIVATE_LINK})
  if(ARG_INSTALL)
    install(TARGETS segslam_${NAME} EXPORT segslamTargets ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
    install(DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR}/
            DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/segslam/${NAME}
            FILES_MATCHING PATTERN "*.h" PATTERN "*_internal.h" EXCLUDE)
  endif()
endfunction()

# segslam_add_test(NAME SRCS ... LINK ... [LABELS ...] [TIMEOUT s] [FIXTURE name])
# A GoogleTest executable whose tests are registered with CTest one by one; FIXTURE
# names a CTest fixture (e.g. generated datasets) every test of it requires.
function(segslam_add_test NAME)
  cmake_parse_arguments(ARG "" "TIMEOUT;FIXTURE" "SRCS;LINK;LABELS" ${ARGN})
  add_executable(${NAME} ${ARG_SRCS})
  target_link_libraries(${NAME} PRIVATE ${ARG_LINK} GTest::gtest GTest::gtest_main)
  target_compile_definitions(${NAME} PRIVATE
    SEGSLAM_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    SEGSLAM_SHARED_DATA_DIR="${PROJECT_SOURCE_DIR}/../shared/data")
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 600)
  endif()
  set(properties TIMEOUT ${ARG_TIMEOUT})
  if(ARG_LABELS)
    list(APPEND properties LABELS "${ARG_LABELS}")
  endif()
  if(ARG_FIXTURE)
    list(APPEND properties FIXTURES_REQUIRED ${ARG_FIXTURE})
  endif()
  gtest_discover_tests(${NAME}
    WORKING_DIRECTORY ${PROJECT_BINARY_DIR}
    PROPERTIES ${properties}
    DISCOVERY_TIMEOUT 60)
endfunction()
