# What a user of Stride gets, in the build tree (add_subdirectory) and installed
# (cmake --install build --prefix P, then find_package(Stride 0.1) with P in CMAKE_PREFIX_PATH):
# the libraries as Stride::<module>, their headers under include/stride mirroring the source tree,
# the generated LCM headers, the programs, the robot and controller configurations.
include(CMakePackageConfigHelpers)

# Libraries a user may link, by module: stride_<module> is Stride::<module> in both cases.
set(STRIDE_EXPORTED_MODULES
  multibody contact ocp ddp   # solver/: the numerical core, free of I/O
  terrain                     # terrain files, surface and contact queries, elevation grids
  config                      # robot YAML (+ URDF, SRDF) loader
  messages                    # LCM types and their validation
  signing                     # authenticated messages (libsodium's HMAC, OpenSSL's SHA-256)
  controller                  # stride-mpc's library: the tick, the node, its configuration
  sim sim_node                # the mock robot's physics; its LCM node
  log_segments drive)         # tools/: command segments; controller + mock robot in one process
set(_stride_targets stride_abi)
set_target_properties(stride_abi PROPERTIES EXPORT_NAME abi)
add_library(Stride::abi ALIAS stride_abi)
foreach(_m IN LISTS STRIDE_EXPORTED_MODULES)
  set_target_properties(stride_${_m} PROPERTIES EXPORT_NAME ${_m})
  add_library(Stride::${_m} ALIAS stride_${_m})
  list(APPEND _stride_targets stride_${_m})
endforeach()

# Stride::solver: the whole numerical core (Stride::ddp pulls in ocp, contact and multibody).
add_library(stride_solver INTERFACE)
target_link_libraries(stride_solver INTERFACE stride_ddp)
set_target_properties(stride_solver PROPERTIES EXPORT_NAME solver)
add_library(Stride::solver ALIAS stride_solver)
# Stride::stride: everything.
add_library(stride_all INTERFACE)
target_link_libraries(stride_all INTERFACE stride_solver stride_terrain stride_config stride_messages
                      stride_signing stride_controller stride_sim stride_sim_node stride_drive)
set_target_properties(stride_all PROPERTIES EXPORT_NAME stride)
add_library(Stride::stride ALIAS stride_all)
list(APPEND _stride_targets stride_solver stride_all)

# A project that adds Stride with add_subdirectory(... EXCLUDE_FROM_ALL) does not build the
# programs, which the rules below install: its own install would fail on them.
if(NOT STRIDE_INSTALL)
  return()
endif()

install(TARGETS ${_stride_targets} EXPORT StrideTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})

# Headers of the exported modules, at the paths they are included by ("solver/ocp/knot.hpp").
foreach(_dir solver/multibody solver/contact solver/ocp solver/ddp terrain config messages controller sim
             tools/log tools/drive)
  file(GLOB _headers CONFIGURE_DEPENDS ${STRIDE_ROOT}/${_dir}/*.hpp)
  # The programs' shared options (stride_sim_cli) are not a library a user links.
  list(FILTER _headers EXCLUDE REGEX "sim/command_line.hpp$")
  install(FILES ${_headers} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/stride/${_dir})
endforeach()

# The programs (stride-bench and the tests' helpers stay in the build tree).
install(TARGETS stride-mpc stride-sim stride-drive stride-teleop stride-log-summary stride-keygen
                stride-check-dynamics stride-dynamics-demo stride-paper-astronaut
                stride-paper-large-stride stride-viz
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
# stride-viz's page (viz/web's bundle), when it was built; stride-viz finds it there from bin/.
install(DIRECTORY ${STRIDE_VIZ_WEB_DIR}/
  DESTINATION ${CMAKE_INSTALL_DATADIR}/stride/viz/web OPTIONAL)
# What the programs read: robots (YAML + URDF), controller configurations, drives, plans. A
# controller YAML names its robot by a relative path (../robots/...), so the tree is kept as is.
install(DIRECTORY ${STRIDE_ROOT}/config/robots ${STRIDE_ROOT}/config/controller
                  ${STRIDE_ROOT}/config/commands ${STRIDE_ROOT}/config/plans
                  ${STRIDE_ROOT}/config/terrain
  DESTINATION ${CMAKE_INSTALL_DATADIR}/stride/config)

# The package: targets, the config file that finds their dependencies, the version file.
set(STRIDE_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/Stride)
set(STRIDE_INSTALL_DATADIR ${CMAKE_INSTALL_DATADIR}/stride)
install(EXPORT StrideTargets NAMESPACE Stride:: DESTINATION ${STRIDE_CMAKE_DIR})
configure_package_config_file(${STRIDE_ROOT}/cmake/StrideConfig.cmake.in
  ${PROJECT_BINARY_DIR}/StrideConfig.cmake
  INSTALL_DESTINATION ${STRIDE_CMAKE_DIR}
  PATH_VARS STRIDE_INSTALL_DATADIR)
# 0.x: a minor version may break the API, so 0.1 accepts 0.1.* only.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/StrideConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/StrideConfig.cmake
              ${PROJECT_BINARY_DIR}/StrideConfigVersion.cmake
              ${STRIDE_ROOT}/cmake/FindLCM.cmake ${STRIDE_ROOT}/cmake/FindTinyXML.cmake
  DESTINATION ${STRIDE_CMAKE_DIR})
