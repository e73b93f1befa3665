# bench_registration: the registration benchmark, with PCL NDT and GICP as peers.
gmm_add_tool(bench_registration
  SOURCES src/tools/bench/bench_registration.cpp src/tools/bench/bench_data.cpp
          src/tools/bench/bench_peers.cpp
  LIBS gmm_core ${PCL_LIBRARIES})
target_include_directories(bench_registration SYSTEM PRIVATE ${PCL_INCLUDE_DIRS})
target_compile_definitions(bench_registration PRIVATE ${PCL_DEFINITIONS})
