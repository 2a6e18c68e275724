#include "engine/archive/analysis_product.h"

#include <algorithm>
#include <type_traits>

#include "engine/archive/hdf5_util.h"
#include "engine/archive/product_fields.h"
#include "engine/archive/provenance.h"
#include "engine/common/errors.h"
#include "engine/common/request_error.h"

namespace gesweep {
namespace {

static_assert(std::is_same_v<hid_t, std::int64_t>, "ProductGroup holds HDF5 identifiers as int64");

using hdf5::Check;
using hdf5::Handle;

// The file (little-endian) and memory types of a stored number type.
struct NumberTypes {
  hid_t file;
  hid_t memory;
};
template <typename T>
NumberTypes TypesOf() {
  if constexpr (std::is_same_v<T, double>) {
    return {H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE};
  } else if constexpr (std::is_same_v<T, std::int8_t>) {
    return {H5T_STD_I8LE, H5T_NATIVE_INT8};
  } else if constexpr (std::is_same_v<T, std::int32_t>) {
    return {H5T_STD_I32LE, H5T_NATIVE_INT32};
  } else {
    static_assert(std::is_same_v<T, std::int64_t>, "a product stores double, int8, int32 or int64");
    return {H5T_STD_I64LE, H5T_NATIVE_INT64};
  }
}

// The manifest's name of a stored number type (ProductField::type).
template <typename T>
std::string_view TypeName() {
  if constexpr (std::is_same_v<T, double>) {
    return "float64";
  } else if constexpr (std::is_same_v<T, std::int8_t>) {
    return "int8";
  } else if constexpr (std::is_same_v<T, std::int32_t>) {
    return "int32";
  } else {
    return "int64";
  }
}

}  // namespace

std::string Filled(std::string_view text, std::string_view placeholder, const std::string& value) {
  std::string out(text);
  const std::size_t at = out.find(placeholder);
  if (at != std::string::npos) out.replace(at, placeholder.size(), value);
  return out;
}

void ProductObject::Attribute(const std::string& name, const std::string& value) {
  hdf5::WriteAttribute(id_, name, value);
}
void ProductObject::Attribute(const std::string& name, const char* value) {
  hdf5::WriteAttribute(id_, name, value);
}
void ProductObject::Attribute(const std::string& name, std::int64_t value) {
  hdf5::WriteAttribute(id_, name, value);
}
void ProductObject::Attribute(const std::string& name, double value) {
  hdf5::WriteAttribute(id_, name, value);
}
void ProductObject::Attribute(const std::string& name, const std::vector<std::string>& values) {
  hdf5::WriteAttribute(id_, name, values);
}
void ProductObject::Attribute(const std::string& name, const std::vector<double>& values) {
  hdf5::WriteAttribute(id_, name, values);
}
void ProductObject::Attribute(const std::string& name, const std::vector<std::int64_t>& values) {
  hdf5::WriteAttribute(id_, name, values);
}

ProductGroup::ProductGroup(ProductGroup&& other) noexcept
    : ProductObject(other.id_), datasets_(std::move(other.datasets_)) {
  other.id_ = H5I_INVALID_HID;
  other.datasets_.clear();
}

ProductGroup::~ProductGroup() {
  for (const std::int64_t id : datasets_) H5Dclose(id);
  if (id_ >= 0) H5Gclose(id_);
}

template <typename T>
ProductDataset ProductGroup::Numbers(const std::string& name, const std::vector<T>& values,
                                     const std::string& units, const std::string& description,
                                     const std::vector<std::size_t>& dims) {
  std::vector<hsize_t> shape;
  std::size_t count = 1;
  for (const std::size_t d : dims) {
    shape.push_back(d);
    count *= d;
  }
  if (shape.empty()) {
    shape.push_back(values.size());
    count = values.size();
  }
  GESWEEP_DEMAND(count == values.size());
  Handle space(H5Screate_simple(static_cast<int>(shape.size()), shape.data(), nullptr),
               "dataspace of " + name);
  const hid_t id =
      H5Dcreate2(id_, name.c_str(), TypesOf<T>().file, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  Check(id, "create " + name);
  datasets_.push_back(id);
  if (count > 0)
    Check(H5Dwrite(id, TypesOf<T>().memory, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), "write " + name);
  ProductDataset dataset(id);
  dataset.Attribute("units", units);
  dataset.Attribute("description", description);
  return dataset;
}

template <typename T>
ProductDataset ProductGroup::Numbers(const ProductField& field, const std::vector<T>& values,
                                     const std::vector<std::size_t>& dims) {
  GESWEEP_DEMAND(field.type == TypeName<T>());
  return Numbers(std::string(field.name), values, std::string(field.units), std::string(field.description),
                 dims);
}

// The element types Numbers stores (analysis_product.h), one explicit instantiation each.
#define GESWEEP_INSTANTIATE_NUMBERS(T)                                                         \
  template ProductDataset ProductGroup::Numbers<T>(const std::string&, const std::vector<T>&,  \
                                                   const std::string&, const std::string&,     \
                                                   const std::vector<std::size_t>&);           \
  template ProductDataset ProductGroup::Numbers<T>(const ProductField&, const std::vector<T>&, \
                                                   const std::vector<std::size_t>&)
GESWEEP_INSTANTIATE_NUMBERS(double);
GESWEEP_INSTANTIATE_NUMBERS(std::int8_t);
GESWEEP_INSTANTIATE_NUMBERS(std::int32_t);
GESWEEP_INSTANTIATE_NUMBERS(std::int64_t);
#undef GESWEEP_INSTANTIATE_NUMBERS

ProductDataset ProductGroup::Strings(const std::string& name, const std::vector<std::string>& values,
                                     const std::string& description) {
  Handle type(H5Tcopy(H5T_C_S1), "string type");
  Check(H5Tset_size(type.get(), H5T_VARIABLE), "string size");
  Check(H5Tset_cset(type.get(), H5T_CSET_UTF8), "string charset");
  std::vector<const char*> pointers;
  pointers.reserve(values.size());
  for (const auto& value : values) pointers.push_back(value.c_str());
  const hsize_t dims[1] = {values.size()};
  Handle space(H5Screate_simple(1, dims, nullptr), "dataspace of " + name);
  const hid_t id =
      H5Dcreate2(id_, name.c_str(), type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  Check(id, "create " + name);
  datasets_.push_back(id);
  if (!values.empty())
    Check(H5Dwrite(id, type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, pointers.data()), "write " + name);
  ProductDataset dataset(id);
  dataset.Attribute("units", "1");
  dataset.Attribute("description", description);
  return dataset;
}

ProductDataset ProductGroup::Strings(const ProductField& field, const std::vector<std::string>& values) {
  GESWEEP_DEMAND(field.type == "string" && field.units == "1");
  return Strings(std::string(field.name), values, std::string(field.description));
}

ProductGroup ProductGroup::Group(const std::string& name) {
  const hid_t id = H5Gcreate2(id_, name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  Check(id, "create group " + name);
  return ProductGroup(id);
}

void WriteProvenance(ProductGroup& group, const ProductLayout& layout, const std::string& command_line) {
  namespace shared = product::shared::attribute;
  const auto listed = [&layout](const ProductField& field) {
    return std::any_of(layout.attributes.begin(), layout.attributes.end(),
                       [&field](const ProductField& f) { return f.name == field.name; });
  };
  GESWEEP_DEMAND(listed(shared::kEngineVersion) && listed(shared::kCreated) && listed(shared::kCommandLine));
  group.Attribute(shared::kEngineVersion, EngineVersion());
  if (listed(shared::kGitCommit)) group.Attribute(shared::kGitCommit, EngineGitCommit());
  group.Attribute(shared::kCreated, UtcTimestamp());
  group.Attribute(shared::kCommandLine, command_line);
}

void WriteAnalysisProduct(const std::filesystem::path& archive, const std::string& path,
                          const std::string& printable, const std::function<void(ProductGroup&)>& write) {
  hdf5::Quiet();
  const std::string shown = archive.string();
  Handle fapl = hdf5::FileAccess();
  const hid_t id = H5Fopen(archive.c_str(), H5F_ACC_RDWR, fapl.get());
  if (id < 0) {
    const std::string detail = hdf5::LastError();
    H5Eclear2(H5E_DEFAULT);
    throw RequestError(shown, "", "",
                       "cannot open the archive for writing (HDF5: " + detail +
                           "); is another program reading or writing it?",
                       printable.empty() ? "" : "no_write", printable);
  }
  Handle file(id);
  hdf5::ReplaceGroup(file.get(), path, [&](const std::string& temporary) {
    const hid_t group = H5Gcreate2(file.get(), temporary.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    Check(group, "create group " + temporary);
    ProductGroup product(group);
    write(product);
  });
  file.Close("close " + shown);
}

}  // namespace gesweep
