# Directory layout shared by the build tree and the install tree, so that every tool finds its data
# the same way (pmg::dataDir(), include/pmg/common/data_paths.hpp): executables in bin/, data in
# share/pmg/ next to it. No source path is compiled into a binary.
#
#   build tree                                 install tree (cmake --install build --prefix P)
#   build/bin/<tools>                          P/bin/<tools>
#   build/share/pmg/config -> <checkout>/config  P/share/pmg/config   (copies)
#   build/share/pmg/data   -> <checkout>/data    P/share/pmg/data
#   build/share/pmg/scripts/<helper>.py -> ...   P/share/pmg/scripts/<helper>.py
#
# The build tree's links make edits in a checkout visible at once. Must be included before the
# targets are defined (it sets their install RPATH).
include(GNUInstallDirs)

set(PMG_INSTALL_DATADIR "${CMAKE_INSTALL_DATADIR}/pmg")
set(PMG_INSTALL_CMAKEDIR "${CMAKE_INSTALL_LIBDIR}/cmake/pmg")
if(NOT PMG_INSTALL_DATADIR STREQUAL "share/pmg" OR NOT CMAKE_INSTALL_BINDIR STREQUAL "bin")
  message(WARNING "pmg: tools look for their data in <exe dir>/../share/pmg; with "
                  "CMAKE_INSTALL_BINDIR='${CMAKE_INSTALL_BINDIR}' and CMAKE_INSTALL_DATADIR='${CMAKE_INSTALL_DATADIR}' "
                  "set PMG_DATA_DIR at run time")
endif()

# Installed executables find the installed libraries (ONNX Runtime when it is the copy in
# third_party/) relative to themselves, never in the build or source tree.
file(RELATIVE_PATH _pmg_bin_to_lib "/${CMAKE_INSTALL_BINDIR}" "/${CMAKE_INSTALL_LIBDIR}")
set(CMAKE_INSTALL_RPATH "$ORIGIN/${_pmg_bin_to_lib}")

# Python helpers the tools call or that plot their outputs; installed into share/pmg/scripts and
# found by the tools through pmg::resolveData("scripts/<name>").
set(PMG_HELPER_SCRIPTS
  ${PMG_SOURCE_DIR}/scripts/calib_plot.py
  ${PMG_SOURCE_DIR}/scripts/plot_joint_calibration.py
  ${PMG_SOURCE_DIR}/scripts/gco_plot.py
  ${PMG_SOURCE_DIR}/scripts/motion_plot_clips.py
  ${PMG_SOURCE_DIR}/scripts/motion_plot_retarget.py
  ${PMG_SOURCE_DIR}/scripts/plot_teleop_trial.py
  ${PMG_SOURCE_DIR}/scripts/render_sil.sh
  ${PMG_SOURCE_DIR}/apps/calib/pmg_plot_zero.py
  ${PMG_SOURCE_DIR}/apps/hal/plot_bus_plan.py
  ${PMG_SOURCE_DIR}/apps/hal/plot_jitter.py
)

# The build tree's data directory: links into the checkout.
set(PMG_BUILD_DATADIR "${CMAKE_BINARY_DIR}/share/pmg")
file(MAKE_DIRECTORY "${PMG_BUILD_DATADIR}/scripts")
foreach(_pmg_dir config data)
  file(CREATE_LINK "${PMG_SOURCE_DIR}/${_pmg_dir}" "${PMG_BUILD_DATADIR}/${_pmg_dir}" SYMBOLIC)
endforeach()
foreach(_pmg_script ${PMG_HELPER_SCRIPTS})
  get_filename_component(_pmg_name "${_pmg_script}" NAME)
  file(CREATE_LINK "${_pmg_script}" "${PMG_BUILD_DATADIR}/scripts/${_pmg_name}" SYMBOLIC)
endforeach()
