# Included after find_package(mujoco), here and by segslamConfig.cmake: Debian 12's
# mujocoConfig.cmake lists /usr/include/libqhull_r/, which the package does not install,
# and CMake refuses an imported target with a missing include path. Drop that path.
get_target_property(_segslam_mujoco_inc mujoco::mujoco INTERFACE_INCLUDE_DIRECTORIES)
if(_segslam_mujoco_inc)
  list(FILTER _segslam_mujoco_inc EXCLUDE REGEX "libqhull_r")
  set_target_properties(mujoco::mujoco PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${_segslam_mujoco_inc}")
endif()
unset(_segslam_mujoco_inc)
