# Small helpers shared by every CMakeLists.txt of the project.

# Adds every immediate subfolder of DIR that has a CMakeLists.txt, in name order. For work on
# one part of the tree, -DRSLAM_ONLY="bus;odometry" adds only subfolders with those names.
function(rslam_add_subdirectories dir)
  file(GLOB children LIST_DIRECTORIES true RELATIVE ${CMAKE_CURRENT_SOURCE_DIR}/${dir}
       ${CMAKE_CURRENT_SOURCE_DIR}/${dir}/*)
  list(SORT children)
  foreach(child ${children})
    if(RSLAM_ONLY AND NOT child IN_LIST RSLAM_ONLY)
      continue()
    endif()
    if(EXISTS ${CMAKE_CURRENT_SOURCE_DIR}/${dir}/${child}/CMakeLists.txt)
      add_subdirectory(${dir}/${child})
    endif()
  endforeach()
endfunction()

# rslam_add_test(NAME name SOURCES a.cc ... LIBS lib ... [LABELS unit|integration|system ...]
#                [TIMEOUT seconds] [RESOURCE_LOCK name])
# One GoogleTest binary in build/bin, each TEST() registered with ctest on its own so ctest -j
# runs them in parallel. Tests get RSLAM_SOURCE_DIR and RSLAM_SHARED_DATA in their environment.
# Tests that hold the same RESOURCE_LOCK never run at the same time (whole pipelines of
# processes: two of them at once overload 2 cores, and a camera at a set rate then loses frames).
function(rslam_add_test)
  cmake_parse_arguments(T "" "NAME;TIMEOUT;RESOURCE_LOCK" "SOURCES;LIBS;LABELS" ${ARGN})
  if(NOT RSLAM_BUILD_TESTS)
    return()
  endif()
  if(NOT T_LABELS)
    set(T_LABELS unit)
  endif()
  if(NOT T_TIMEOUT)
    set(T_TIMEOUT 300)
  endif()
  add_executable(${T_NAME} ${T_SOURCES})
  target_link_libraries(${T_NAME} PRIVATE ${T_LIBS} GTest::gtest GTest::gtest_main GTest::gmock)
  target_compile_definitions(${T_NAME} PRIVATE
    RSLAM_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    RSLAM_BINARY_DIR="${PROJECT_BINARY_DIR}")
  set(lock "")
  if(T_RESOURCE_LOCK)
    set(lock RESOURCE_LOCK ${T_RESOURCE_LOCK})
  endif()
  gtest_discover_tests(${T_NAME}
    DISCOVERY_TIMEOUT 60
    PROPERTIES LABELS "${T_LABELS}" TIMEOUT ${T_TIMEOUT} ${lock}
               ENVIRONMENT "RSLAM_SHARED_DATA=${PROJECT_SOURCE_DIR}/../shared/data")
endfunction()

# rslam_add_benchmark(NAME name SOURCES a.cc ... LIBS lib ...): a Google Benchmark binary in
# build/bin; run it with --benchmark_format=json.
function(rslam_add_benchmark)
  cmake_parse_arguments(B "" "NAME" "SOURCES;LIBS" ${ARGN})
  if(NOT RSLAM_BUILD_BENCHMARKS)
    return()
  endif()
  add_executable(${B_NAME} ${B_SOURCES})
  target_link_libraries(${B_NAME} PRIVATE ${B_LIBS} benchmark::benchmark benchmark::benchmark_main)
  target_compile_definitions(${B_NAME} PRIVATE RSLAM_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
endfunction()

# rslam_add_protos(TARGET a.proto ...): compiles .proto files (paths relative to the current
# folder) into TARGET. protoc runs from the repository root, so a proto imports another by its
# repository path ("common/math/pose2d.proto") and its header is included by its repository path
# ("services/explorer/proto/explorer_state.pb.h"), generated under <build>/generated.
function(rslam_add_protos target)
  set(out ${PROJECT_BINARY_DIR}/generated)
  foreach(proto ${ARGN})
    file(RELATIVE_PATH rel ${PROJECT_SOURCE_DIR} ${CMAKE_CURRENT_SOURCE_DIR}/${proto})
    string(REGEX REPLACE "\\.proto$" "" stem ${rel})
    add_custom_command(
      OUTPUT ${out}/${stem}.pb.cc ${out}/${stem}.pb.h
      COMMAND ${CMAKE_COMMAND} -E make_directory ${out}
      COMMAND protobuf::protoc --cpp_out=${out} -I ${PROJECT_SOURCE_DIR} ${PROJECT_SOURCE_DIR}/${rel}
      DEPENDS ${PROJECT_SOURCE_DIR}/${rel} protobuf::protoc
      COMMENT "protoc ${rel}"
      VERBATIM)
    target_sources(${target} PRIVATE ${out}/${stem}.pb.cc)
  endforeach()
  target_include_directories(${target} PUBLIC ${out})
  target_link_libraries(${target} PUBLIC protobuf::libprotobuf)
endfunction()
