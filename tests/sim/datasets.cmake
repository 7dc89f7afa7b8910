# Datasets that the dataset checks read, each generated once per ctest run by a CTest
# fixture (so test processes share them), into build/test_data/<name>.
set(SEGSLAM_TEST_DATA_DIR ${PROJECT_BINARY_DIR}/test_data)

# segslam_add_test_dataset(NAME SCENARIO ARGS ...)
function(segslam_add_test_dataset NAME SCENARIO)
  add_test(NAME generate_${NAME}
    COMMAND segslam generate ${PROJECT_SOURCE_DIR}/${SCENARIO}
            --out ${SEGSLAM_TEST_DATA_DIR}/${NAME} --force --quiet ${ARGN})
  set_tests_properties(generate_${NAME} PROPERTIES FIXTURES_SETUP sim_datasets TIMEOUT 900)
endfunction()

# Noise-free, with moving objects: re-projection, masks, tracks, pass-2 changes.
segslam_add_test_dataset(city_clean scenarios/city_street_grid.yaml
  --frames 40 --set sensor.enabled=false)
segslam_add_test_dataset(office_clean scenarios/office_walking_xyz.yaml
  --frames 40 --set sensor.enabled=false)
# Default sensor noise: the independent odometry and ORB texture checks.
segslam_add_test_dataset(city_static scenarios/city_street_grid.yaml
  --frames 120 --set city.moving_cars=0 --set city.pedestrians=0)
segslam_add_test_dataset(office_noisy scenarios/office_walking_xyz.yaml --frames 40)

segslam_add_test(sim_dataset_tests
  SRCS dataset_generator_test.cpp
  LINK segslam_sim segslam_scenes segslam_core opencv_features2d opencv_rgbd opencv_imgproc
  FIXTURE sim_datasets)
target_compile_definitions(sim_dataset_tests PRIVATE
  SEGSLAM_TEST_DATA_DIR="${SEGSLAM_TEST_DATA_DIR}")

# The segmentation refinement's acceptance (tests/seg/seg_eval_test.cpp): default sensor
# noise, both passes of the city and the office with walking people.
segslam_add_test_dataset(city_seg scenarios/city_street_grid.yaml --frames 80)
segslam_add_test_dataset(office_seg scenarios/office_walking_xyz.yaml --frames 80)

# The SLAM core's checks (tests/harness/slam_run_test.cpp): a static office with the
# default sensor noise; city_static, city_seg and office_seg above serve too.
segslam_add_test_dataset(office_static scenarios/office_walking_xyz.yaml
  --frames 90 --set office.people_walking=0)
# Hand-held rotation with a walker who comes close and covers much of the view around
# frame 157: there plain SLAM follows the walker.
segslam_add_test_dataset(office_rpy scenarios/office_walking_rpy.yaml --frames 200)
