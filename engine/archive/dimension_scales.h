#pragma once
/// The netCDF view of an archive (schemas/archive.md, "netCDF view"): HDF5 dimension scales (H5DS)
/// that give every per-run dataset named dimensions, so that netCDF-4 readers (xarray's h5netcdf
/// engine, ncdump) see `run`, a vector's index and a series' time axis instead of invented ones.

#include <hdf5.h>

#include <string>
#include <vector>

namespace gesweep::archive {

/// Name of the root dimension of every per-run dataset's first axis.
inline constexpr const char* kRunDimension = "run";

/// The root dimension of the second axis of the vector result column at `path`
/// ("results/modes/eigenvalues" -> "modes_eigenvalues_index").
std::string VectorDimensionName(const std::string& path);

/// Creates the dimensions of the per-run datasets `paths` of `file` (which hold `runs` rows each) and
/// attaches them, in the order of `paths`: /run (a netCDF dimension without values) to axis 0 of
/// every dataset; a series' `time_axis` dataset, made a coordinate variable, to axis 1 of the series;
/// a root dimension without values (VectorDimensionName) to axis 1 of any other vector. Then it
/// links every design column into each results/<analysis> and series/<analysis> group and names
/// them in CF's `coordinates` attribute of the group's datasets (netCDF readers make them
/// coordinates of `run`; a name the group already uses is not linked). The
/// attributes hold object references (file addresses): call it in a fixed order before any run data,
/// and before SWMR writing starts.
void AttachDimensionScales(hid_t file, std::int64_t runs, const std::vector<std::string>& paths);

/// Whether an attribute is one of the dimension scale attributes AttachDimensionScales writes (they
/// hold object references of their own file, and are not copied to another file).
bool IsDimensionScaleAttribute(const std::string& name);

}  // namespace gesweep::archive
