# Installed programs find libsim relative to themselves ($ORIGIN/../lib…), so an install into any
# prefix (cmake --install build --prefix DIR) runs without LD_LIBRARY_PATH. The Debian packages
# install into /usr, where the loader finds the library anyway; they turn this off (lintian
# rejects a redundant RPATH).
option(SIM_INSTALL_RPATH "Give installed programs an RPATH relative to themselves" ON)
if(SIM_INSTALL_RPATH AND NOT DEFINED CMAKE_INSTALL_RPATH)
  # Relative path from bin/ to lib/ as the install layout has it (lib, lib64, lib/<multiarch>).
  file(RELATIVE_PATH _sim_bin_to_lib "/prefix/${CMAKE_INSTALL_BINDIR}" "/prefix/${CMAKE_INSTALL_LIBDIR}")
  set(CMAKE_INSTALL_RPATH "$ORIGIN/${_sim_bin_to_lib}")
  unset(_sim_bin_to_lib)
endif()
