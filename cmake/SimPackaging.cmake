# Debian packages with CPack, one per install component:
#   libsim0       runtime   libsim.so.0
#   libsim-dev    dev       headers, libsim.a, CMake package, sim.pc / sim_static.pc
#   sim-tools     tools     sim_ls, sim_echo, sim_rm, sim_dump, the drivers and replay tools, configs
#   python3-sim   python    the Python module `sim` (numpy views of frames)
# Build them with scripts/build-debs.sh (configures with CMAKE_INSTALL_PREFIX=/usr, runs cpack).
# Library dependencies come from dpkg-shlibdeps; the others are declared below.
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME sim)
set(CPACK_PACKAGE_VENDOR "SIM project")
set(CPACK_PACKAGE_CONTACT "SIM maintainers <sim@localhost>")
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "${PROJECT_DESCRIPTION}")
set(CPACK_PACKAGE_DIRECTORY ${PROJECT_BINARY_DIR}/packages)
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_COMPONENTS_ALL runtime dev tools)
if(TARGET sim_python)
  list(APPEND CPACK_COMPONENTS_ALL python)
endif()

set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
# The programs need libsim.so.0, which is in no installed package yet: let dpkg-shlibdeps find it
# in the build tree (the tools package depends on libsim0 explicitly, below).
get_target_property(_sim_library_dir sim_shared BINARY_DIR)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS_PRIVATE_DIRS ${_sim_library_dir})
unset(_sim_library_dir)
set(CPACK_DEBIAN_PACKAGE_SECTION libs)
set(CPACK_DEBIAN_PACKAGE_RELEASE 1)
set(_sim_deb_version "${PROJECT_VERSION}-${CPACK_DEBIAN_PACKAGE_RELEASE}")

set(CPACK_DEBIAN_RUNTIME_PACKAGE_NAME libsim${PROJECT_VERSION_MAJOR})
set(CPACK_DEBIAN_RUNTIME_PACKAGE_SECTION libs)
set(CPACK_DEBIAN_RUNTIME_DESCRIPTION "Sensor-in-Memory: shared-memory transport for sensor frames (library)
 One named POSIX shared-memory region per stream, one writer, a lock-free two-slot seqlock;
 readers copy or borrow the freshest complete frame, never a torn one.")
set(CPACK_DEBIAN_RUNTIME_PACKAGE_GENERATE_SHLIBS ON)

set(CPACK_DEBIAN_DEV_PACKAGE_NAME libsim-dev)
set(CPACK_DEBIAN_DEV_PACKAGE_SECTION libdevel)
set(CPACK_DEBIAN_DEV_PACKAGE_DEPENDS
    "libsim${PROJECT_VERSION_MAJOR} (= ${_sim_deb_version}), libxxhash-dev, pkgconf | pkg-config")
set(CPACK_DEBIAN_DEV_DESCRIPTION "Sensor-in-Memory: development files
 Headers (C: sim/sim.h, C++17/20: sim/sim.hpp), the static library, the CMake package
 (find_package(sim)) and pkg-config files (sim, sim_static).")

set(CPACK_DEBIAN_TOOLS_PACKAGE_NAME sim-tools)
set(CPACK_DEBIAN_TOOLS_PACKAGE_SECTION utils)
set(CPACK_DEBIAN_TOOLS_PACKAGE_DEPENDS "libsim${PROJECT_VERSION_MAJOR} (= ${_sim_deb_version})")
set(CPACK_DEBIAN_TOOLS_DESCRIPTION "Sensor-in-Memory: tools, sensor drivers and replay programs
 sim_ls, sim_echo, sim_rm, sim_dump; the Hesai, Unitree and camera drivers; pcap, video and
 serial replay; sensor configurations in /usr/share/sim/config.")

set(CPACK_DEBIAN_PYTHON_PACKAGE_NAME python3-sim)
set(CPACK_DEBIAN_PYTHON_PACKAGE_SECTION python)
set(CPACK_DEBIAN_PYTHON_PACKAGE_DEPENDS "${SIM_PYTHON_DEB_DEPENDS}")
set(CPACK_DEBIAN_PYTHON_DESCRIPTION "Sensor-in-Memory: Python module
 import sim: readers and writers of SIM streams with frames as numpy arrays, including
 read-only zero-copy views that keep the shared memory mapped while they live.")
unset(_sim_deb_version)

include(CPack)
