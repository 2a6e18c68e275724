#include "engine/archive/dimension_scales.h"

#include <hdf5_hl.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <map>

#include "engine/archive/archive_format.h"
#include "engine/archive/hdf5_util.h"

namespace gesweep::archive {
namespace {

using hdf5::Check;
using hdf5::Handle;

// netCDF-4's mark of a dimension that is not a variable (netCDF-C's nc4hdf.c writes the dimension's
// length after it, as "%10d"; readers compare the prefix).
constexpr const char* kNotAVariable = "This is a netCDF dimension but not a netCDF variable.";

// A dimension without values at the root: a float32 dataset of `length` elements that is never
// written (no storage is allocated), marked as a scale with netCDF's NAME.
void CreatePureDimension(hid_t file, const std::string& name, std::int64_t length,
                         const std::string& description) {
  const hsize_t dims[1] = {static_cast<hsize_t>(length)};
  Handle space(H5Screate_simple(1, dims, nullptr), "dimension space");
  Handle dcpl(H5Pcreate(H5P_DATASET_CREATE), "dimension creation properties");
  Check(H5Pset_fill_time(dcpl.get(), H5D_FILL_TIME_NEVER), "dimension fill time");
  Handle d(H5Dcreate2(file, name.c_str(), H5T_IEEE_F32LE, space.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT),
           "create dimension " + name);
  char label[96];
  std::snprintf(label, sizeof(label), "%s%10lld", kNotAVariable, static_cast<long long>(length));
  Check(H5DSset_scale(d.get(), label), "make " + name + " a dimension");
  hdf5::WriteAttribute(d.get(), "units", "1");
  hdf5::WriteAttribute(d.get(), "description", description);
}

bool IsVectorOrSeries(hid_t dataset) { return hdf5::Dimensions(dataset).size() == 2; }

std::string Parent(const std::string& path) { return path.substr(0, path.rfind('/')); }
std::string Leaf(const std::string& path) { return path.substr(path.rfind('/') + 1); }

bool Below(const std::string& path, const char* group) {
  const std::string prefix = std::string(group) + "/";
  return path.compare(0, prefix.size(), prefix) == 0;
}

// A second name `link` of the object at `target` (a hard link: the same object, no copy).
void HardLink(hid_t file, const std::string& target, const std::string& link) {
  Check(H5Lcreate_hard(file, target.c_str(), file, link.c_str(), H5P_DEFAULT, H5P_DEFAULT),
        "link " + target + " as " + link);
}

// The design columns as coordinates of `run` in every results/<analysis> and series/<analysis>
// group: netCDF groups do not share variables, so each group gets hard links to the design
// datasets (the same objects: no copy) and CF's `coordinates` attribute on its data variables.
// A design column whose name a group already uses (series/open_loop/height_m) is not linked there.
void LinkDesignCoordinates(hid_t file, const std::vector<std::string>& paths) {
  std::vector<std::string> design;
  std::map<std::string, std::vector<std::string>> groups;  // group -> its per-run data variables
  for (const std::string& path : paths) {
    if (Below(path, kDesignGroup)) design.push_back(path);
    if (Below(path, kResultsGroup) || Below(path, kSeriesGroup)) groups[Parent(path)].push_back(path);
  }
  // In name order: the same attribute for a run's layout order and a merge's listing order.
  std::sort(design.begin(), design.end());
  for (const auto& [group, variables] : groups) {
    std::string names;
    for (const std::string& column : design) {
      const std::string link = group + "/" + Leaf(column);
      if (hdf5::Exists(file, link)) continue;
      HardLink(file, column, link);
      names += (names.empty() ? "" : " ") + Leaf(column);
    }
    if (names.empty()) continue;
    for (const std::string& path : variables) {
      Handle d(H5Dopen2(file, path.c_str(), H5P_DEFAULT), "open " + path);
      hdf5::WriteAttribute(d.get(), "coordinates", names);
    }
  }
}

}  // namespace

std::string VectorDimensionName(const std::string& path) {
  std::string below = path.substr(path.find('/') + 1);  // <analysis>/<name>
  for (char& c : below) {
    if (c == '/') c = '_';
  }
  return below + "_index";
}

bool IsDimensionScaleAttribute(const std::string& name) {
  return name == "CLASS" || name == "NAME" || name == "REFERENCE_LIST" || name == "DIMENSION_LIST";
}

void AttachDimensionScales(hid_t file, std::int64_t runs, const std::vector<std::string>& paths) {
  CreatePureDimension(file, kRunDimension, runs,
                      "The netCDF dimension of the runs: axis 0 of every per-run dataset; no stored values");
  std::map<std::string, Handle> scales;
  scales.emplace(kRunDimension, Handle(H5Dopen2(file, kRunDimension, H5P_DEFAULT), "open dimension run"));
  // The scale `dimension` (one of `scales`) as axis `index` of the dataset `d` at `path`.
  auto attach = [&](const Handle& d, const std::string& path, const std::string& dimension, unsigned index) {
    Check(H5DSattach_scale(d.get(), scales.at(dimension).get(), index),
          "attach " + dimension + " to " + path);
  };
  for (const std::string& path : paths) {
    Handle d(H5Dopen2(file, path.c_str(), H5P_DEFAULT), "open " + path);
    attach(d, path, kRunDimension, 0);
    if (!IsVectorOrSeries(d.get())) continue;
    const auto axis = hdf5::ReadStringAttribute(d.get(), "time_axis");
    std::string dimension;
    if (axis) {
      dimension = *axis;
      if (scales.find(dimension) == scales.end()) {
        Handle t(H5Dopen2(file, dimension.c_str(), H5P_DEFAULT), "open time axis " + dimension);
        // A coordinate variable: a scale whose NAME is its own name.
        const std::string leaf = dimension.substr(dimension.rfind('/') + 1);
        Check(H5DSset_scale(t.get(), leaf.c_str()), "make " + dimension + " a dimension");
        scales.emplace(dimension, std::move(t));
      }
    } else {
      dimension = VectorDimensionName(path);
      if (scales.find(dimension) == scales.end()) {
        CreatePureDimension(
            file, dimension, hdf5::Dimensions(d.get())[1],
            "The netCDF dimension of axis 1 of " + path + " (its component_names); no stored values");
        scales.emplace(dimension,
                       Handle(H5Dopen2(file, dimension.c_str(), H5P_DEFAULT), "open " + dimension));
      }
    }
    attach(d, path, dimension, 1);
  }
  LinkDesignCoordinates(file, paths);
}

}  // namespace gesweep::archive
