# `cmake --install build --prefix P` and find_package(pmg) (layout: cmake/PmgLayout.cmake):
#   P/bin                executables, pmg_plot_tracking.py
#   P/lib                the component libraries (+ ONNX Runtime when it is the copy in third_party/)
#   P/include            public headers: pmg/..., pmg_lcm/... (generated LCM types)
#   P/share/pmg          config/, data/, scripts/ (what pmg::dataDir() finds)
#   P/lib/cmake/pmg      pmgConfig.cmake, pmgConfigVersion.cmake, pmgTargets.cmake
# A consumer writes find_package(pmg) and links pmg::<component> (pmg::common, pmg::generator,
# pmg::policy, ...), the same names as inside this build. Included at the end of the top-level
# CMakeLists.txt, after every target exists: new library targets under src/ are exported without
# being listed here.
include(CMakePackageConfigHelpers)

# Targets defined in @p dir and below.
function(pmg_targets_below dir out)
  get_property(targets DIRECTORY "${dir}" PROPERTY BUILDSYSTEM_TARGETS)
  get_property(subdirs DIRECTORY "${dir}" PROPERTY SUBDIRECTORIES)
  foreach(sub ${subdirs})
    pmg_targets_below("${sub}" sub_targets)
    list(APPEND targets ${sub_targets})
  endforeach()
  set(${out} ${targets} PARENT_SCOPE)
endfunction()

# Include directories in the source or build tree are build-only: consumers get <prefix>/include.
function(pmg_build_only_includes target)
  foreach(prop INTERFACE_INCLUDE_DIRECTORIES INTERFACE_SYSTEM_INCLUDE_DIRECTORIES)
    get_target_property(dirs ${target} ${prop})
    if(NOT dirs)
      continue()
    endif()
    set(fixed)
    foreach(d ${dirs})
      cmake_path(IS_PREFIX PMG_SOURCE_DIR "${d}" NORMALIZE in_source)
      cmake_path(IS_PREFIX CMAKE_BINARY_DIR "${d}" NORMALIZE in_build)
      if(NOT d MATCHES "^\\$<" AND (in_source OR in_build))
        list(APPEND fixed "$<BUILD_INTERFACE:${d}>")
      else()
        list(APPEND fixed "${d}")
      endif()
    endforeach()
    set_property(TARGET ${target} PROPERTY ${prop} "${fixed}")
  endforeach()
endfunction()

# Libraries: every pmg_* library of src/ and lcmtypes/ and the dependency wrappers pmg_deps_*.
# Export name: pmg_<name>[_core|_lib] -> pmg::<name> (pmg_controller_core -> pmg::controller).
pmg_targets_below("${PMG_SOURCE_DIR}/src" _pmg_src_targets)
pmg_targets_below("${PMG_SOURCE_DIR}/lcmtypes" _pmg_lcm_targets)
get_property(_pmg_top_targets DIRECTORY "${PMG_SOURCE_DIR}" PROPERTY BUILDSYSTEM_TARGETS)
set(PMG_EXPORTED_LIBRARIES)
foreach(t ${_pmg_src_targets} ${_pmg_lcm_targets} ${_pmg_top_targets})
  get_target_property(type ${t} TYPE)
  if(NOT type MATCHES "^(STATIC_LIBRARY|SHARED_LIBRARY|INTERFACE_LIBRARY)$" OR NOT t MATCHES "^pmg_")
    continue()
  endif()
  string(REGEX REPLACE "^pmg_" "" name "${t}")
  string(REGEX REPLACE "_(core|lib)$" "" name "${name}")
  set_target_properties(${t} PROPERTIES EXPORT_NAME ${name})
  pmg_build_only_includes(${t})
  list(APPEND PMG_EXPORTED_LIBRARIES ${t})
endforeach()
install(TARGETS ${PMG_EXPORTED_LIBRARIES} EXPORT pmgTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})

# Executables of apps/ and bench/ (tests stay in the build tree).
pmg_targets_below("${PMG_SOURCE_DIR}/apps" _pmg_app_targets)
if(PMG_BUILD_BENCHMARKS)
  pmg_targets_below("${PMG_SOURCE_DIR}/bench" _pmg_bench_targets)
endif()
set(PMG_INSTALLED_EXECUTABLES)
foreach(t ${_pmg_app_targets} ${_pmg_bench_targets})
  get_target_property(type ${t} TYPE)
  if(type STREQUAL "EXECUTABLE")
    list(APPEND PMG_INSTALLED_EXECUTABLES ${t})
  endif()
endforeach()
install(TARGETS ${PMG_INSTALLED_EXECUTABLES} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(PROGRAMS ${PMG_SOURCE_DIR}/apps/controller/pmg_plot_tracking.py DESTINATION ${CMAKE_INSTALL_BINDIR})

# Headers, data, helper scripts.
install(DIRECTORY ${PMG_SOURCE_DIR}/include/pmg DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY ${CMAKE_BINARY_DIR}/lcmtypes/pmg_lcm DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
        FILES_MATCHING PATTERN "*.hpp")
install(DIRECTORY ${PMG_SOURCE_DIR}/config ${PMG_SOURCE_DIR}/data DESTINATION ${PMG_INSTALL_DATADIR}
        PATTERN "__pycache__" EXCLUDE)
install(PROGRAMS ${PMG_HELPER_SCRIPTS} DESTINATION ${PMG_INSTALL_DATADIR}/scripts)
install(FILES ${PMG_SOURCE_DIR}/LICENSE DESTINATION ${CMAKE_INSTALL_DATADIR}/doc/pmg)

# ONNX Runtime: the copy in third_party/ goes to lib/ with its SONAME links.
if(PMG_ONNXRUNTIME_IN_SOURCE_TREE)
  get_filename_component(_pmg_ort_dir "${ONNXRUNTIME_LIBRARY}" DIRECTORY)
  install(DIRECTORY ${_pmg_ort_dir}/ DESTINATION ${CMAKE_INSTALL_LIBDIR} FILES_MATCHING PATTERN "libonnxruntime.so*")
endif()

# The package: targets, config (finds the dependencies), version.
set(PMG_HAVE_RENDER OFF)
if(TARGET pmg_render)
  set(PMG_HAVE_RENDER ON)
endif()
install(EXPORT pmgTargets NAMESPACE pmg:: DESTINATION ${PMG_INSTALL_CMAKEDIR})
configure_package_config_file(${PMG_SOURCE_DIR}/cmake/pmgConfig.cmake.in ${CMAKE_BINARY_DIR}/pmgConfig.cmake
                              INSTALL_DESTINATION ${PMG_INSTALL_CMAKEDIR}
                              PATH_VARS PMG_INSTALL_DATADIR CMAKE_INSTALL_INCLUDEDIR)
write_basic_package_version_file(${CMAKE_BINARY_DIR}/pmgConfigVersion.cmake COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_BINARY_DIR}/pmgConfig.cmake ${CMAKE_BINARY_DIR}/pmgConfigVersion.cmake
        DESTINATION ${PMG_INSTALL_CMAKEDIR})
