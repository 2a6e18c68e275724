#include "engine/archive/column_reader.h"

#include <algorithm>
#include <cstring>

#include "engine/archive/archive_format.h"
#include "engine/archive/archive_reader.h"
#include "engine/archive/hdf5_util.h"

namespace gesweep {
namespace {

using hdf5::Check;
using hdf5::Handle;

StoredType StoredTypeOf(hid_t type) {
  switch (H5Tget_class(type)) {
    case H5T_FLOAT:
      return StoredType::kFloat;
    case H5T_INTEGER:
      return H5Tget_sign(type) == H5T_SGN_NONE ? StoredType::kUnsignedInteger : StoredType::kSignedInteger;
    case H5T_STRING:
      return StoredType::kText;
    case H5T_COMPOUND:
      return StoredType::kCompound;
    default:
      return StoredType::kOther;
  }
}

Handle VariableStringType() {
  Handle type(H5Tcopy(H5T_C_S1), "string type");
  Check(H5Tset_size(type.get(), H5T_VARIABLE), "string size");
  Check(H5Tset_cset(type.get(), H5T_CSET_UTF8), "string charset");
  return type;
}

// The strings of an attribute of string type, fixed or variable length, scalar or a list.
std::vector<std::string> ReadTexts(hid_t attribute, hid_t file_type, std::size_t count,
                                   const std::string& what) {
  std::vector<std::string> texts;
  if (count == 0) return texts;
  if (H5Tis_variable_str(file_type) > 0) {
    Handle type = VariableStringType();
    std::vector<char*> pointers(count, nullptr);
    Check(H5Aread(attribute, type.get(), pointers.data()), "read " + what);
    for (char* pointer : pointers) {
      texts.emplace_back(pointer ? pointer : "");
      H5free_memory(pointer);
    }
    return texts;
  }
  const std::size_t size = H5Tget_size(file_type);
  std::vector<char> buffer(size * count + 1, '\0');
  Check(H5Aread(attribute, file_type, buffer.data()), "read " + what);
  for (std::size_t i = 0; i < count; ++i) {
    const char* text = buffer.data() + i * size;
    texts.emplace_back(text, strnlen(text, size));
  }
  return texts;
}

// One attribute of an open object, read whole.
AttributeValue ReadAttribute(hid_t object, const std::string& name, const std::string& where) {
  const std::string what = "attribute " + name + " of " + where;
  AttributeValue value;
  value.name = name;
  Handle attribute(H5Aopen(object, name.c_str(), H5P_DEFAULT), "open " + what);
  Handle type(H5Aget_type(attribute.get()), "type of " + what);
  Handle space(H5Aget_space(attribute.get()), "space of " + what);
  const H5S_class_t space_class = H5Sget_simple_extent_type(space.get());
  value.scalar = space_class == H5S_SCALAR;
  const hssize_t points = H5Sget_simple_extent_npoints(space.get());
  Check(points, "size of " + what);
  const auto count = space_class == H5S_NULL ? std::size_t{0} : static_cast<std::size_t>(points);
  switch (H5Tget_class(type.get())) {
    case H5T_STRING:
      value.kind = AttributeValue::Kind::kText;
      value.texts = ReadTexts(attribute.get(), type.get(), count, what);
      break;
    case H5T_INTEGER:
    case H5T_FLOAT:
      value.kind = H5Tget_class(type.get()) == H5T_INTEGER ? AttributeValue::Kind::kInteger
                                                           : AttributeValue::Kind::kFloat;
      value.numbers.resize(count);
      if (count > 0) Check(H5Aread(attribute.get(), H5T_NATIVE_DOUBLE, value.numbers.data()), "read " + what);
      break;
    default:
      value.kind = AttributeValue::Kind::kOther;
      break;
  }
  return value;
}

// The attribute `name` of the object at `path`, or nullopt when the object has none.
std::optional<AttributeValue> FindAttribute(const ArchiveReader& archive, const std::string& path,
                                            const std::string& name) {
  const std::string where = path + " of " + archive.path().string();
  Handle object(H5Oopen(archive.file(), path.c_str(), H5P_DEFAULT), "open " + where);
  const htri_t exists = H5Aexists(object.get(), name.c_str());
  Check(exists, "look up attribute " + name + " of " + where);
  if (exists == 0) return std::nullopt;
  return ReadAttribute(object.get(), name, where);
}

}  // namespace

std::vector<DatasetInfo> DescribeDatasets(const ArchiveReader& archive) {
  std::vector<DatasetInfo> datasets;
  for (const std::string& path : archive.Datasets()) {
    const std::string where = path + " of " + archive.path().string();
    Handle dataset(H5Dopen2(archive.file(), path.c_str(), H5P_DEFAULT), "open " + where);
    Handle type(H5Dget_type(dataset.get()), "type of " + where);
    DatasetInfo info;
    info.path = path;
    info.shape = hdf5::Dimensions(dataset.get());
    info.type = StoredTypeOf(type.get());
    info.element_bytes = H5Tget_size(type.get());
    auto text = [&](const char* name) -> std::string {
      const htri_t exists = H5Aexists(dataset.get(), name);
      if (exists <= 0) return "";
      const AttributeValue value = ReadAttribute(dataset.get(), name, where);
      return value.kind == AttributeValue::Kind::kText && value.texts.size() == 1 ? value.texts[0] : "";
    };
    info.units = text("units");
    info.description = text("description");
    info.time_axis = text("time_axis");
    if (H5Aexists(dataset.get(), "levels") > 0) {
      const AttributeValue levels = ReadAttribute(dataset.get(), "levels", where);
      if (levels.kind == AttributeValue::Kind::kText) info.levels = levels.texts;
    }
    if (info.type == StoredType::kSignedInteger || info.type == StoredType::kUnsignedInteger) {
      if (H5Aexists(dataset.get(), "fill") > 0) {
        const AttributeValue fill = ReadAttribute(dataset.get(), "fill", where);
        if (fill.kind == AttributeValue::Kind::kInteger && fill.numbers.size() == 1)
          info.fill = static_cast<std::int64_t>(fill.numbers[0]);
      }
    }
    H5Eclear2(H5E_DEFAULT);
    datasets.push_back(std::move(info));
  }
  return datasets;
}

void ReadDoubleRows(const ArchiveReader& archive, const std::string& path, std::int64_t first,
                    std::int64_t count, std::vector<double>& out) {
  out.resize(static_cast<std::size_t>(count));
  if (count > 0) archive.ReadRows(path, first, count, H5T_NATIVE_DOUBLE, out.data());
}

void ReadUnsignedRows(const ArchiveReader& archive, const std::string& path, std::int64_t first,
                      std::int64_t count, std::vector<std::uint64_t>& out) {
  out.resize(static_cast<std::size_t>(count));
  if (count > 0) archive.ReadRows(path, first, count, H5T_NATIVE_UINT64, out.data());
}

std::vector<std::string> ReadTextRows(const ArchiveReader& archive, const std::string& path,
                                      std::int64_t first, std::int64_t count) {
  if (path == archive::kRunMessage) return archive.ReadMessages(first, count);
  std::vector<std::string> texts;
  if (count <= 0) return texts;
  const std::string where = path + " of " + archive.path().string();
  Handle dataset(H5Dopen2(archive.file(), path.c_str(), H5P_DEFAULT), "open " + where);
  Handle file_type(H5Dget_type(dataset.get()), "type of " + where);
  if (H5Tget_class(file_type.get()) != H5T_STRING) throw ArchiveError(where + " is not text");
  const auto n = static_cast<std::size_t>(count);
  texts.reserve(n);
  if (H5Tis_variable_str(file_type.get()) > 0) {
    Handle type = VariableStringType();
    std::vector<char*> pointers(n, nullptr);
    archive.ReadRows(path, first, count, type.get(), pointers.data());
    for (char* pointer : pointers) {
      texts.emplace_back(pointer ? pointer : "");
      H5free_memory(pointer);
    }
    return texts;
  }
  const std::size_t size = H5Tget_size(file_type.get());
  std::vector<char> buffer(size * n);
  archive.ReadRows(path, first, count, file_type.get(), buffer.data());
  for (std::size_t i = 0; i < n; ++i) {
    const char* text = buffer.data() + i * size;
    texts.emplace_back(text, strnlen(text, size));
  }
  return texts;
}

std::vector<AttributeValue> ReadObjectAttributes(const ArchiveReader& archive, const std::string& path) {
  const std::string where = path + " of " + archive.path().string();
  Handle object(H5Oopen(archive.file(), path.c_str(), H5P_DEFAULT), "open " + where);
  H5O_info_t info;
  Check(H5Oget_info2(object.get(), &info, H5O_INFO_NUM_ATTRS), "attributes of " + where);
  std::vector<AttributeValue> attributes;
  for (hsize_t i = 0; i < info.num_attrs; ++i) {
    const ssize_t length =
        H5Aget_name_by_idx(object.get(), ".", H5_INDEX_NAME, H5_ITER_INC, i, nullptr, 0, H5P_DEFAULT);
    Check(length, "attribute name of " + where);
    std::string name(static_cast<std::size_t>(length), '\0');
    Check(H5Aget_name_by_idx(object.get(), ".", H5_INDEX_NAME, H5_ITER_INC, i, name.data(), name.size() + 1,
                             H5P_DEFAULT),
          "attribute name of " + where);
    attributes.push_back(ReadAttribute(object.get(), name, where));
  }
  return attributes;
}

std::vector<std::string> ReadStringListAttribute(const ArchiveReader& archive, const std::string& path,
                                                 const std::string& name) {
  const auto value = FindAttribute(archive, path, name);
  if (!value) return {};
  if (value->kind != AttributeValue::Kind::kText) {
    throw ArchiveError("attribute " + name + " of " + path + " of " + archive.path().string() +
                       " is not text");
  }
  return value->texts;
}

std::vector<double> ReadDoubleListAttribute(const ArchiveReader& archive, const std::string& path,
                                            const std::string& name) {
  const auto value = FindAttribute(archive, path, name);
  if (!value) return {};
  if (value->kind != AttributeValue::Kind::kInteger && value->kind != AttributeValue::Kind::kFloat) {
    throw ArchiveError("attribute " + name + " of " + path + " of " + archive.path().string() +
                       " is not numeric");
  }
  return value->numbers;
}

}  // namespace gesweep
