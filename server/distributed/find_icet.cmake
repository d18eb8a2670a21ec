# IceT, the sort-last compositor ParaView ships (Debian's paraview-dev installs it under
# /usr/include/paraview-*/vtkicet). Sets ICET_INCLUDE_DIR, ICET_CONFIG_DIR, ICET_CORE_LIBRARY,
# ICET_MPI_LIBRARY and ICET_FOUND. Used by the probe and by the project alike.
file(GLOB peakcast_icet_hints /usr/include/paraview-*/vtkicet/src/include /usr/include/paraview-*/vtkicet)
find_path(ICET_INCLUDE_DIR IceT.h HINTS ${peakcast_icet_hints})
find_path(ICET_CONFIG_DIR IceTConfig.h HINTS ${peakcast_icet_hints})
find_library(ICET_CORE_LIBRARY NAMES vtkIceTCore-pv5.11 IceTCore)
find_library(ICET_MPI_LIBRARY NAMES vtkIceTMPI-pv5.11 IceTMPI)
if(ICET_INCLUDE_DIR AND ICET_CONFIG_DIR AND ICET_CORE_LIBRARY AND ICET_MPI_LIBRARY)
  set(ICET_FOUND TRUE)
else()
  set(ICET_FOUND FALSE)
endif()
