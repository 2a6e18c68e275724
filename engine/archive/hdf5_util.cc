#include "engine/archive/hdf5_util.h"

#include <cctype>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <utility>

#include "engine/archive/dimension_scales.h"

namespace gesweep::hdf5 {
namespace {

// At static initialisation, before the library's first call: no clean-up at exit. HDF5 1.10 closes
// every file still open from an atexit handler, and a file whose close already failed (a full disk)
// makes that handler crash (SIGSEGV in H5F__close_cb) after gesweep has printed its error. The engine
// closes what it opens; the handler adds nothing.
const bool kNoCleanUpAtExit = H5dont_atexit() >= 0;

struct StackText {
  std::string innermost;  // the description of the innermost (first) entry
  int system_error = 0;   // an "errno = N" some entry quotes (HDF5's sec2 driver on a failed write)
};

herr_t CollectEntry(unsigned n, const H5E_error2_t* error, void* data) {
  auto* text = static_cast<StackText*>(data);
  if (error->desc == nullptr) return 0;
  const std::string desc = error->desc;
  if (n == 0) text->innermost = desc;
  const auto at = desc.find("errno = ");
  if (text->system_error == 0 && at != std::string::npos) {
    text->system_error = std::atoi(desc.c_str() + at + 8);
  }
  return 0;
}

// HDF5's descriptions may hold line breaks and a list of "name = value" details; keep the sentence.
std::string FirstClause(std::string text) {
  const auto line = text.find_first_of("\r\n");
  if (line != std::string::npos) text.resize(line);
  const auto details = text.find(", time = ");
  if (details != std::string::npos) text.resize(details);
  while (!text.empty() && (text.back() == ' ' || text.back() == ',')) text.pop_back();
  return text;
}

}  // namespace

void Quiet() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }

std::string LastError() {
  StackText text;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, CollectEntry, &text);
  if (text.system_error > 0) {
    std::string reason = std::strerror(text.system_error);
    if (!reason.empty()) reason[0] = static_cast<char>(std::tolower(static_cast<unsigned char>(reason[0])));
    return reason;
  }
  return FirstClause(text.innermost);
}

std::int64_t Check(std::int64_t status, const std::string& what) {
  if (status < 0) {
    const std::string detail = LastError();
    H5Eclear2(H5E_DEFAULT);
    throw ArchiveError(detail.empty() ? what : what + ": " + detail, detail);
  }
  return status;
}

void Handle::Reset() {
  if (id_ < 0) return;
  switch (H5Iget_type(id_)) {
    case H5I_FILE:
      H5Fclose(id_);
      break;
    case H5I_GROUP:
      H5Gclose(id_);
      break;
    case H5I_DATASET:
      H5Dclose(id_);
      break;
    case H5I_DATASPACE:
      H5Sclose(id_);
      break;
    case H5I_DATATYPE:
      H5Tclose(id_);
      break;
    case H5I_ATTR:
      H5Aclose(id_);
      break;
    case H5I_GENPROP_LST:
      H5Pclose(id_);
      break;
    default:
      break;
  }
  id_ = H5I_INVALID_HID;
}

void Handle::Close(const std::string& what) {
  if (id_ < 0) return;
  herr_t status = 0;
  switch (H5Iget_type(id_)) {
    case H5I_FILE:
      status = H5Fclose(id_);
      break;
    case H5I_DATASET:
      status = H5Dclose(id_);
      break;
    default:
      Reset();
      return;
  }
  id_ = H5I_INVALID_HID;
  Check(status, what);
}

Handle FileAccess() {
  Handle fapl(H5Pcreate(H5P_FILE_ACCESS), "file access property list");
  Check(H5Pset_libver_bounds(fapl.get(), H5F_LIBVER_LATEST, H5F_LIBVER_LATEST), "libver bounds");
  // Lock where the file system supports locks; carry on where it does not (some cluster
  // file systems), instead of failing.
  Check(H5Pset_file_locking(fapl.get(), true, true), "file locking");
  return fapl;
}

namespace {

// Calls `visit` with each prefix of the path `path` ("a", "a/b", "a/b/c" for "/a/b/c") until it
// returns false; returns whether it never did.
template <class Visit>
bool VisitPathPrefixes(const std::string& path, Visit visit) {
  std::string partial;
  std::stringstream stream(path);
  std::string part;
  while (std::getline(stream, part, '/')) {
    if (part.empty()) continue;
    partial += (partial.empty() ? "" : "/") + part;
    if (!visit(partial)) return false;
  }
  return true;
}

}  // namespace

bool Exists(hid_t location, const std::string& path) {
  return VisitPathPrefixes(path, [&](const std::string& partial) {
    return H5Lexists(location, partial.c_str(), H5P_DEFAULT) > 0;
  });
}

void CreateGroups(hid_t location, const std::string& path) {
  VisitPathPrefixes(path, [&](const std::string& partial) {
    if (H5Lexists(location, partial.c_str(), H5P_DEFAULT) <= 0) {
      Handle group(H5Gcreate2(location, partial.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                   "create group " + partial);
    }
    return true;
  });
}

void ReplaceGroup(hid_t file, const std::string& path, const std::function<void(const std::string&)>& write) {
  const std::size_t slash = path.rfind('/');
  const std::string parent = slash == std::string::npos ? "" : path.substr(0, slash);
  const std::string leaf = slash == std::string::npos ? path : path.substr(slash + 1);
  const std::string temporary = (parent.empty() ? "" : parent + "/") + "." + leaf + ".partial";
  if (!parent.empty()) CreateGroups(file, parent);
  if (H5Lexists(file, temporary.c_str(), H5P_DEFAULT) > 0) {
    Check(H5Ldelete(file, temporary.c_str(), H5P_DEFAULT), "delete " + temporary);
  }
  try {
    write(temporary);
  } catch (...) {
    H5Ldelete(file, temporary.c_str(), H5P_DEFAULT);
    H5Eclear2(H5E_DEFAULT);
    throw;
  }
  if (H5Lexists(file, path.c_str(), H5P_DEFAULT) > 0) {
    Check(H5Ldelete(file, path.c_str(), H5P_DEFAULT), "delete the previous " + path);
  }
  Check(H5Lmove(file, temporary.c_str(), file, path.c_str(), H5P_DEFAULT, H5P_DEFAULT),
        "move " + temporary + " to " + path);
}

namespace {

void Replace(hid_t object, const std::string& name) {
  if (H5Aexists(object, name.c_str()) > 0) Check(H5Adelete(object, name.c_str()), "delete attribute " + name);
}

Handle VariableString() {
  Handle type(H5Tcopy(H5T_C_S1), "string type");
  Check(H5Tset_size(type.get(), H5T_VARIABLE), "string size");
  Check(H5Tset_cset(type.get(), H5T_CSET_UTF8), "string charset");
  return type;
}

template <typename T>
void WriteNumbers(hid_t object, const std::string& name, hid_t file_type, hid_t memory_type, const T* values,
                  std::size_t count, bool scalar) {
  Replace(object, name);
  hsize_t dims[1] = {count};
  Handle space(scalar ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, dims, nullptr), "attribute space");
  Handle attribute(H5Acreate2(object, name.c_str(), file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT),
                   "create attribute " + name);
  if (count == 0 && !scalar) return;  // an empty list: nothing to write
  Check(H5Awrite(attribute.get(), memory_type, values), "write attribute " + name);
}

}  // namespace

void WriteAttribute(hid_t object, const std::string& name, const std::string& value) {
  Replace(object, name);
  Handle type = VariableString();
  Handle space(H5Screate(H5S_SCALAR), "attribute space");
  Handle attribute(H5Acreate2(object, name.c_str(), type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT),
                   "create attribute " + name);
  const char* pointer = value.c_str();
  Check(H5Awrite(attribute.get(), type.get(), &pointer), "write attribute " + name);
}

void WriteAttribute(hid_t object, const std::string& name, const char* value) {
  WriteAttribute(object, name, std::string(value));
}

void WriteAttribute(hid_t object, const std::string& name, std::int64_t value) {
  WriteNumbers(object, name, H5T_STD_I64LE, H5T_NATIVE_INT64, &value, 1, true);
}

void WriteAttribute(hid_t object, const std::string& name, double value) {
  WriteNumbers(object, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &value, 1, true);
}

void WriteAttribute(hid_t object, const std::string& name, const std::vector<double>& values) {
  WriteNumbers(object, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, values.data(), values.size(), false);
}

void WriteAttribute(hid_t object, const std::string& name, const std::vector<std::int64_t>& values) {
  WriteNumbers(object, name, H5T_STD_I64LE, H5T_NATIVE_INT64, values.data(), values.size(), false);
}

void WriteAttribute(hid_t object, const std::string& name, const std::vector<std::string>& values) {
  Replace(object, name);
  Handle type = VariableString();
  hsize_t dims[1] = {values.size()};
  Handle space(H5Screate_simple(1, dims, nullptr), "attribute space");
  Handle attribute(H5Acreate2(object, name.c_str(), type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT),
                   "create attribute " + name);
  std::vector<const char*> pointers;
  pointers.reserve(values.size());
  for (const auto& value : values) pointers.push_back(value.c_str());
  if (pointers.empty()) return;  // an empty list: nothing to write
  Check(H5Awrite(attribute.get(), type.get(), pointers.data()), "write attribute " + name);
}

Handle OpenAttribute(hid_t object, const std::string& name) {
  return Handle(H5Aopen(object, name.c_str(), H5P_DEFAULT), "open attribute " + name);
}

void UpdateAttribute(hid_t object, const std::string& name, const std::string& value) {
  Handle attribute = OpenAttribute(object, name);
  Handle type = VariableString();
  const char* pointer = value.c_str();
  Check(H5Awrite(attribute.get(), type.get(), &pointer), "write attribute " + name);
}

void UpdateAttribute(hid_t object, const std::string& name, std::int64_t value) {
  Handle attribute = OpenAttribute(object, name);
  Check(H5Awrite(attribute.get(), H5T_NATIVE_INT64, &value), "write attribute " + name);
}

namespace {

// An attribute and its type in the file.
struct TypedAttribute {
  Handle attribute;
  Handle file_type;
};

// The attribute `name` of `object` and its type in the file; none when it is absent, ArchiveError
// ("attribute <name> is not <what>") when its type is not of class `type_class`.
std::optional<TypedAttribute> OpenAttributeOfClass(hid_t object, const std::string& name,
                                                   H5T_class_t type_class, const std::string& what) {
  if (H5Aexists(object, name.c_str()) <= 0) return std::nullopt;
  Handle attribute = OpenAttribute(object, name);
  Handle file_type(H5Aget_type(attribute.get()), "attribute type");
  if (H5Tget_class(file_type.get()) != type_class)
    throw ArchiveError("attribute " + name + " is not " + what);
  return TypedAttribute{std::move(attribute), std::move(file_type)};
}

}  // namespace

std::optional<std::string> ReadStringAttribute(hid_t object, const std::string& name) {
  const auto found = OpenAttributeOfClass(object, name, H5T_STRING, "a string");
  if (!found) return std::nullopt;
  const Handle& attribute = found->attribute;
  const Handle& file_type = found->file_type;
  Handle space(H5Aget_space(attribute.get()), "attribute space");
  if (H5Sget_simple_extent_npoints(space.get()) != 1)
    throw ArchiveError("attribute " + name + " is not one string");
  if (H5Tis_variable_str(file_type.get()) > 0) {
    Handle type = VariableString();
    char* pointer = nullptr;
    Check(H5Aread(attribute.get(), type.get(), &pointer), "read attribute " + name);
    std::string value = pointer ? pointer : "";
    H5free_memory(pointer);
    return value;
  }
  const std::size_t size = H5Tget_size(file_type.get());
  std::vector<char> buffer(size + 1, '\0');
  Check(H5Aread(attribute.get(), file_type.get(), buffer.data()), "read attribute " + name);
  return std::string(buffer.data(), strnlen(buffer.data(), size));
}

std::optional<std::int64_t> ReadIntegerAttribute(hid_t object, const std::string& name) {
  const auto found = OpenAttributeOfClass(object, name, H5T_INTEGER, "an integer");
  if (!found) return std::nullopt;
  std::int64_t value = 0;
  Check(H5Aread(found->attribute.get(), H5T_NATIVE_INT64, &value), "read attribute " + name);
  return value;
}

std::optional<double> ReadDoubleAttribute(hid_t object, const std::string& name) {
  if (H5Aexists(object, name.c_str()) <= 0) return std::nullopt;
  Handle attribute = OpenAttribute(object, name);
  double value = 0;
  Check(H5Aread(attribute.get(), H5T_NATIVE_DOUBLE, &value), "read attribute " + name);
  return value;
}

std::vector<std::string> ReadStringListAttribute(hid_t object, const std::string& name) {
  if (H5Aexists(object, name.c_str()) <= 0) return {};
  Handle attribute = OpenAttribute(object, name);
  Handle space(H5Aget_space(attribute.get()), "attribute space");
  const auto count = static_cast<std::size_t>(H5Sget_simple_extent_npoints(space.get()));
  if (count == 0) return {};
  Handle type = VariableString();
  std::vector<char*> pointers(count, nullptr);
  Check(H5Aread(attribute.get(), type.get(), pointers.data()), "read attribute " + name);
  std::vector<std::string> values;
  for (char* pointer : pointers) {
    values.emplace_back(pointer ? pointer : "");
    H5free_memory(pointer);
  }
  return values;
}

std::vector<std::int64_t> ReadIntegerListAttribute(hid_t object, const std::string& name) {
  const auto found = OpenAttributeOfClass(object, name, H5T_INTEGER, "an integer");
  if (!found) return {};
  Handle space(H5Aget_space(found->attribute.get()), "attribute space");
  const auto count = static_cast<std::size_t>(H5Sget_simple_extent_npoints(space.get()));
  std::vector<std::int64_t> values(count);
  if (count > 0)
    Check(H5Aread(found->attribute.get(), H5T_NATIVE_INT64, values.data()), "read attribute " + name);
  return values;
}

namespace {

struct CopyContext {
  hid_t to;
  std::string error;
};

herr_t CopyOne(hid_t location, const char* name, const H5A_info_t*, void* data) {
  auto* context = static_cast<CopyContext*>(data);
  // Dimension scale attributes hold object references into their own file: the copy gets its own.
  if (archive::IsDimensionScaleAttribute(name)) return 0;
  try {
    Handle attribute(H5Aopen(location, name, H5P_DEFAULT), std::string("open attribute ") + name);
    Handle type(H5Aget_type(attribute.get()), "attribute type");
    Handle space(H5Aget_space(attribute.get()), "attribute space");
    const auto points = static_cast<std::size_t>(H5Sget_simple_extent_npoints(space.get()));
    std::vector<unsigned char> buffer(H5Tget_size(type.get()) * std::max<std::size_t>(points, 1));
    Replace(context->to, name);
    Handle copy(H5Acreate2(context->to, name, type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT),
                std::string("create attribute ") + name);
    if (points == 0) return 0;
    Check(H5Aread(attribute.get(), type.get(), buffer.data()), std::string("read attribute ") + name);
    Check(H5Awrite(copy.get(), type.get(), buffer.data()), std::string("write attribute ") + name);
    // Variable-length strings were allocated by the read.
    if (H5Tdetect_class(type.get(), H5T_VLEN) > 0 || H5Tis_variable_str(type.get()) > 0) {
      H5Dvlen_reclaim(type.get(), space.get(), H5P_DEFAULT, buffer.data());
    }
  } catch (const ArchiveError& e) {
    context->error = e.what();
    return -1;
  }
  return 0;
}

}  // namespace

void CopyAttributes(hid_t from, hid_t to) {
  CopyContext context{to, ""};
  hsize_t index = 0;
  const herr_t status = H5Aiterate2(from, H5_INDEX_NAME, H5_ITER_INC, &index, CopyOne, &context);
  if (status < 0)
    throw ArchiveError(context.error.empty() ? "copy attributes: " + LastError() : context.error);
}

Handle ComplexType() {
  Handle type(H5Tcreate(H5T_COMPOUND, 2 * sizeof(double)), "complex type");
  Check(H5Tinsert(type.get(), "re", 0, H5T_IEEE_F64LE), "complex re");
  Check(H5Tinsert(type.get(), "im", sizeof(double), H5T_IEEE_F64LE), "complex im");
  return type;
}

Handle FixedStringType(int length) {
  Handle type(H5Tcopy(H5T_C_S1), "string type");
  Check(H5Tset_size(type.get(), static_cast<std::size_t>(length)), "string size");
  Check(H5Tset_strpad(type.get(), H5T_STR_NULLPAD), "string padding");
  Check(H5Tset_cset(type.get(), H5T_CSET_UTF8), "string charset");
  return type;
}

std::vector<std::int64_t> Dimensions(hid_t dataset) {
  Handle space(H5Dget_space(dataset), "dataset space");
  const int rank = H5Sget_simple_extent_ndims(space.get());
  std::vector<hsize_t> dims(static_cast<std::size_t>(std::max(rank, 0)));
  if (rank > 0) H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
  return std::vector<std::int64_t>(dims.begin(), dims.end());
}

Handle SelectRows(hid_t dataset, std::int64_t first, std::int64_t count, Handle* memory) {
  Handle space(H5Dget_space(dataset), "dataset space");
  const int rank = H5Sget_simple_extent_ndims(space.get());
  hsize_t dims[2] = {0, 0};
  H5Sget_simple_extent_dims(space.get(), dims, nullptr);
  hsize_t start[2] = {static_cast<hsize_t>(first), 0};
  hsize_t extent[2] = {static_cast<hsize_t>(count), rank == 2 ? dims[1] : 1};
  Check(H5Sselect_hyperslab(space.get(), H5S_SELECT_SET, start, nullptr, extent, nullptr), "select rows");
  *memory = Handle(H5Screate_simple(rank, extent, nullptr), "memory space");
  return space;
}

}  // namespace gesweep::hdf5
