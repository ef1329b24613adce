# pmg_build_time_optimization(<target>): compile <target>'s own sources at -O1 in optimised builds
# (Release, RelWithDebInfo, MinSizeRel; Debug keeps -O0). For code whose run time is not the
# product's: the tests (test/CMakeLists.txt) and the offline tools (apps/CMakeLists.txt). What they
# run is the libraries' code (src/, -O3 as shipped) and MuJoCo's. Measured on 2 cores: the 21 tools'
# sources took 245 s of CPU at -O1 against 390 s at -O3 (pmg_calib_joints.cpp 20.1 s against 30.6),
# the 82 test sources 459 s against 522 s; CI builds everything from nothing. Floating-point results do not depend on the level (no
# -ffast-math; ISO C++ mode, so no contraction): the byte-identical clip and vector tests hold.
function(pmg_build_time_optimization target)
  target_compile_options(${target} PRIVATE $<$<CONFIG:Release,RelWithDebInfo,MinSizeRel>:-O1>)
endfunction()

# _pmg_directory_targets(<dir> <out-var>): the targets defined in <dir> and below.
function(_pmg_directory_targets dir out)
  get_property(targets DIRECTORY ${dir} PROPERTY BUILDSYSTEM_TARGETS)
  get_property(subdirs DIRECTORY ${dir} PROPERTY SUBDIRECTORIES)
  foreach(sub ${subdirs})
    _pmg_directory_targets(${sub} more)
    list(APPEND targets ${more})
  endforeach()
  set(${out} ${targets} PARENT_SCOPE)
endfunction()
