# All third-party dependencies, found (never vendored). scripts/setup.sh installs them.
find_package(Threads REQUIRED)
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(mujoco REQUIRED)
find_package(NLopt REQUIRED)
find_package(Ceres REQUIRED)
find_package(yaml-cpp REQUIRED)
find_package(fmt REQUIRED)
find_package(PkgConfig REQUIRED)
pkg_check_modules(URDFDOM REQUIRED IMPORTED_TARGET urdfdom)
pkg_check_modules(LCM REQUIRED IMPORTED_TARGET lcm)
pkg_check_modules(OROCOS_KDL REQUIRED IMPORTED_TARGET orocos-kdl)
# kdl_parser: Debian's CMake config needs ROS 2's ament and its .pc file needs ROS 1's rosconsole,
# so find header and library directly (the shared library carries its own dependencies).
find_path(KDL_PARSER_INCLUDE_DIR kdl_parser/kdl_parser.hpp REQUIRED)
find_library(KDL_PARSER_LIBRARY kdl_parser REQUIRED)
find_program(LCM_GEN_EXECUTABLE lcm-gen REQUIRED)
find_package(CLI11 CONFIG REQUIRED)
find_package(pagmo QUIET)
# Teleoperation and authenticated commands (issue 13, docs/teleop.md): SDL2's GameController API
# (pmg_gamepad), libsodium (crypto_auth HMAC on every command channel), Boost.Beast + OpenSSL
# (pmg_vr_bridge's HTTPS/WSS server and its self-signed certificate), nlohmann-json (the page's
# pose messages).
pkg_check_modules(SDL2 REQUIRED IMPORTED_TARGET sdl2)
pkg_check_modules(SODIUM REQUIRED IMPORTED_TARGET libsodium)
find_package(Boost 1.74 REQUIRED)
find_package(OpenSSL REQUIRED)
find_package(nlohmann_json 3.10 REQUIRED)
# Rendering (pmg_render_log): GLFW for an OpenGL context (Xvfb on headless machines), libpng.
find_package(glfw3 3.3 QUIET)
find_package(PNG QUIET)
if(PMG_BUILD_TESTS)
  find_package(GTest REQUIRED)
endif()
if(PMG_BUILD_BENCHMARKS)
  find_package(benchmark REQUIRED)
endif()

add_library(pmg_deps_kdl INTERFACE)
add_library(pmg_deps::kdl ALIAS pmg_deps_kdl)
target_include_directories(pmg_deps_kdl SYSTEM INTERFACE ${KDL_PARSER_INCLUDE_DIR})
target_link_libraries(pmg_deps_kdl INTERFACE ${KDL_PARSER_LIBRARY} PkgConfig::OROCOS_KDL PkgConfig::URDFDOM Eigen3::Eigen)

# ONNX Runtime: -DONNXRUNTIME_ROOT=<official release> (include/, lib/) or the copy that
# scripts/setup.sh unpacks into third_party/onnxruntime.
set(ONNXRUNTIME_ROOT "${PMG_SOURCE_DIR}/third_party/onnxruntime" CACHE PATH "ONNX Runtime root (include/ + lib/)")
find_path(ONNXRUNTIME_INCLUDE_DIR onnxruntime_c_api.h
          PATHS ${ONNXRUNTIME_ROOT}/include ${ONNXRUNTIME_ROOT}/include/onnxruntime NO_DEFAULT_PATH)
find_library(ONNXRUNTIME_LIBRARY NAMES onnxruntime PATHS ${ONNXRUNTIME_ROOT}/lib NO_DEFAULT_PATH)
if(NOT ONNXRUNTIME_INCLUDE_DIR OR NOT ONNXRUNTIME_LIBRARY)
  message(FATAL_ERROR "ONNX Runtime not found under ONNXRUNTIME_ROOT='${ONNXRUNTIME_ROOT}'. "
                      "Run scripts/setup.sh or pass -DONNXRUNTIME_ROOT=<release dir with include/ and lib/>.")
endif()
add_library(pmg_deps_onnxruntime INTERFACE)
add_library(pmg_deps::onnxruntime ALIAS pmg_deps_onnxruntime)
target_include_directories(pmg_deps_onnxruntime SYSTEM INTERFACE $<BUILD_INTERFACE:${ONNXRUNTIME_INCLUDE_DIR}>)
# The copy in third_party/ is installed with pmg (lib/, cmake/PmgInstall.cmake); an official release
# elsewhere stays where it is and the installed executables get its folder in their RPATH.
cmake_path(IS_PREFIX PMG_SOURCE_DIR "${ONNXRUNTIME_LIBRARY}" NORMALIZE PMG_ONNXRUNTIME_IN_SOURCE_TREE)
if(PMG_ONNXRUNTIME_IN_SOURCE_TREE)
  get_filename_component(_pmg_ort_name "${ONNXRUNTIME_LIBRARY}" NAME)
  target_link_libraries(pmg_deps_onnxruntime INTERFACE
    $<BUILD_INTERFACE:${ONNXRUNTIME_LIBRARY}>
    $<INSTALL_INTERFACE:$<INSTALL_PREFIX>/${CMAKE_INSTALL_LIBDIR}/${_pmg_ort_name}>)
else()
  target_link_libraries(pmg_deps_onnxruntime INTERFACE ${ONNXRUNTIME_LIBRARY})
  get_filename_component(_pmg_ort_dir "${ONNXRUNTIME_LIBRARY}" DIRECTORY)
  list(APPEND CMAKE_INSTALL_RPATH "${_pmg_ort_dir}")
endif()
