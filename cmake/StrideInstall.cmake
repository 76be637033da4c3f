# What a user of Stride gets, in the build tree (add_subdirectory) and installed
# (cmake --install build --prefix P, then find_package(Stride 0.1) with P in CMAKE_PREFIX_PATH):
# the libraries as Stride::<module>, their headers as <stride/...> mirroring the source tree
# (<stride/solver/ocp/knot.hpp>), the generated LCM headers (<stride/robot_state_t.hpp>), the
# programs, the robot and controller configurations. cmake/README.md, "Headers": why and how.

include(CMakePackageConfigHelpers)

# Libraries a user may link, by module: stride_<module> is Stride::<module> in both cases.
set(STRIDE_EXPORTED_MODULES
  multibody contact ocp ddp   # solver/: the numerical core, free of I/O
  terrain                     # terrain files, surface and contact queries, elevation grids
  config                      # robot YAML (+ URDF, SRDF) loader
  locomotion                  # the planner: gaits, contact timeline, gait generator, problem
  messages                    # LCM types and their validation
  policy                      # a received policy interpolated: u_ff + K (x_ref ⊖ x) (messages/)
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
target_link_libraries(stride_all INTERFACE stride_solver stride_terrain stride_config
                      stride_locomotion stride_messages stride_policy stride_signing stride_controller
                      stride_sim stride_sim_node stride_drive)
set_target_properties(stride_all PROPERTIES EXPORT_NAME stride)
add_library(Stride::stride ALIAS stride_all)
list(APPEND _stride_targets stride_solver stride_all)

# The public headers: the exported modules' headers, as <stride/DIR/NAME.hpp>, and the LCM types'
# (messages/, generated), as <stride/TYPE.hpp>. Stride's own code includes the first from the
# repository root ("solver/ocp/knot.hpp": include_directories in the top-level CMakeLists.txt), a
# user cannot: the targets give users include/ only (installed) or the build tree's view of it,
# ${STRIDE_INCLUDE_VIEW}, where each header is copied with its includes rewritten to <stride/...>
# (cmake/StrideRewriteHeader.cmake), so that the installed headers need no other include
# directory.
set(STRIDE_INCLUDE_VIEW ${PROJECT_BINARY_DIR}/include)
set(_stride_public_list ${PROJECT_BINARY_DIR}/stride_public_headers.txt)
set(_stride_view_headers "")
set(_stride_public "")
foreach(_dir solver/multibody solver/contact solver/ocp solver/ddp terrain config locomotion messages
             controller sim tools/log tools/drive)
  file(GLOB _headers CONFIGURE_DEPENDS ${STRIDE_ROOT}/${_dir}/*.hpp)
  # The programs' shared options (stride_sim_cli) are not a library a user links.
  list(FILTER _headers EXCLUDE REGEX "sim/command_line.hpp$")
  foreach(_header IN LISTS _headers)
    file(RELATIVE_PATH _rel ${STRIDE_ROOT} ${_header})
    set(_out ${STRIDE_INCLUDE_VIEW}/stride/${_rel})
    add_custom_command(OUTPUT ${_out}
      COMMAND ${CMAKE_COMMAND} -DSTRIDE_HEADER_IN=${_header} -DSTRIDE_HEADER_OUT=${_out}
              -DSTRIDE_HEADER_LIST=${_stride_public_list}
              -P ${CMAKE_CURRENT_LIST_DIR}/StrideRewriteHeader.cmake
      DEPENDS ${_header} ${_stride_public_list} ${CMAKE_CURRENT_LIST_DIR}/StrideRewriteHeader.cmake
      VERBATIM)
    list(APPEND _stride_view_headers ${_out})
    list(APPEND _stride_public stride/${_rel})
    # Installed from the view, at include/stride/<the same path>.
    if(STRIDE_INSTALL)
      install(FILES ${_out} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/stride/${_dir})
    endif()
  endforeach()
endforeach()
# The LCM headers are generated as stride/TYPE.hpp already (messages/CMakeLists.txt, which puts
# their directory on Stride::messages' build interface and installs them in include/stride).
get_directory_property(_lcm_types DIRECTORY ${STRIDE_ROOT}/messages DEFINITION STRIDE_LCM_TYPES)
foreach(_t IN LISTS _lcm_types)
  list(APPEND _stride_public stride/${_t}.hpp)
endforeach()
# Rewritten only when the set of headers changes (file(CONFIGURE) leaves an equal file alone).
list(JOIN _stride_public "\n" _stride_public_lines)
file(CONFIGURE OUTPUT ${_stride_public_list} CONTENT "${_stride_public_lines}\n" @ONLY)
add_custom_target(stride_headers ALL DEPENDS ${_stride_view_headers})
# Every Stride library links stride_abi: the users of any of them get include/ (never the
# repository root, nor include/stride), and the view is complete before they compile (an interface
# library's dependencies are followed by the targets that link it).
target_include_directories(stride_abi INTERFACE
  $<BUILD_INTERFACE:${STRIDE_INCLUDE_VIEW}> $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
add_dependencies(stride_abi stride_headers)

# A project that adds Stride with add_subdirectory(... EXCLUDE_FROM_ALL) does not build the
# programs, which the rules below install: its own install would fail on them.
if(NOT STRIDE_INSTALL)
  return()
endif()

install(TARGETS ${_stride_targets} EXPORT StrideTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})

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
