#pragma once
/// Derived products of an archive under /analysis (schemas/archive.md): the stability boundary
/// (`gesweep boundary --archive`), sensitivity indices (`gesweep sensitivity`), the dispersion
/// (`gesweep dispersion`). One way to write them, so that every product is written the same
/// safe way: the archive opened for writing (one line naming it when another program holds it),
/// the product built under a temporary name and moved over the old one only when complete
/// (hdf5::ReplaceGroup), the file closed with errors reported. The callers write their product's
/// fields, described in schemas/products.json (engine/archive/product_fields.h, generated from it),
/// with the small API below and never see HDF5.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "engine/common/copy_rules.h"

namespace gesweep {

/// One dataset or attribute of a product (or of a subset-simulation archive), described once in
/// schemas/products.json, from which the build generates one constant per field
/// (engine/archive/product_fields.h: product::<product>::attribute::k..., ::dataset::k...): its
/// writer stores it under this name with these units and this description (ProductGroup::Numbers and
/// Strings below), and the column manifest lists it (`gesweep columns --json`, "products" and
/// "subset_archive"), which the Python reader of archives reads its layout from. A name in
/// <angle brackets> stands for a family (`<key>`: one dataset per key, named by it).
struct ProductField {
  std::string_view name;
  std::string_view type;   ///< float64, int8, int32, int64, string; an attribute may be "list of ..."
  std::string_view units;  ///< a dataset's `units` attribute; "" for an attribute
  std::string_view shape;  ///< its dimensions ("point", "group, column"); "" for a scalar attribute
  std::string_view description;
};

/// The layout of a product: where it is, what writes it, its attributes, datasets and subgroups.
struct ProductLayout {
  std::string_view name;  ///< what the readers call it ("boundary")
  std::string_view path;  ///< its group ("analysis/boundary"); a subgroup's is relative to its parent
  std::string_view written_by;
  std::string_view description;
  std::vector<ProductField> attributes;
  std::vector<ProductField> datasets;
  std::vector<ProductLayout> groups;
};

/// `text` (a field's name, units or description) with its `placeholder` ("<level>") replaced by `value`.
std::string Filled(std::string_view text, std::string_view placeholder, const std::string& value);

/// An HDF5 object of a product being written (a dataset or a group): its attributes.
class ProductObject {
 public:
  void Attribute(const std::string& name, const std::string& value);
  void Attribute(const std::string& name, const char* value);
  void Attribute(const std::string& name, std::int64_t value);
  void Attribute(const std::string& name, double value);
  void Attribute(const std::string& name, const std::vector<std::string>& values);
  void Attribute(const std::string& name, const std::vector<double>& values);
  void Attribute(const std::string& name, const std::vector<std::int64_t>& values);
  /// The attribute `field` describes (ProductLayout::attributes).
  template <typename V>
  void Attribute(const ProductField& field, const V& value) {
    Attribute(std::string(field.name), value);
  }

 protected:
  explicit ProductObject(std::int64_t id) : id_(id) {}
  std::int64_t id_;  // the open object (an HDF5 identifier)
};

/// A dataset of a product being written: more attributes can be added. Its identifier is owned by
/// the group that made it.
class ProductDataset : public ProductObject {
 private:
  friend class ProductGroup;
  explicit ProductDataset(std::int64_t id) : ProductObject(id) {}
};

/// A group of a product being written (valid only inside WriteAnalysisProduct's callback).
class ProductGroup : public ProductObject {
 public:
  /// A dataset of `values` (row-major) of shape `dims` (empty: 1-D of values.size()), stored as
  /// little-endian float64 / int8 / int32 / int64, with its units and description.
  template <typename T>
  ProductDataset Numbers(const std::string& name, const std::vector<T>& values, const std::string& units,
                         const std::string& description, const std::vector<std::size_t>& dims = {});
  /// The same, named and described by `field` (its type must be that of T).
  template <typename T>
  ProductDataset Numbers(const ProductField& field, const std::vector<T>& values,
                         const std::vector<std::size_t>& dims = {});
  /// A 1-D dataset of variable-length UTF-8 strings (units "1").
  ProductDataset Strings(const std::string& name, const std::vector<std::string>& values,
                         const std::string& description);
  /// The same, named and described by `field` (of type string).
  ProductDataset Strings(const ProductField& field, const std::vector<std::string>& values);
  /// A subgroup.
  ProductGroup Group(const std::string& name);

  GESWEEP_MOVE_CONSTRUCT_ONLY(ProductGroup);
  ~ProductGroup();

 private:
  friend void WriteAnalysisProduct(const std::filesystem::path&, const std::string&, const std::string&,
                                   const std::function<void(ProductGroup&)>&);
  explicit ProductGroup(std::int64_t id) : ProductObject(id) {}
  std::vector<std::int64_t> datasets_;  // datasets made here, closed with the group
};

/// Stores in `group` the provenance attributes of product `layout` (product::shared::attribute of
/// engine/archive/product_fields.h): engine_version (this engine's), created (now), command_line, and
/// git_commit (this engine's commit) when the layout lists it. The layout must list the other three.
void WriteProvenance(ProductGroup& group, const ProductLayout& layout, const std::string& command_line);

/// Writes the product `path` (e.g. "analysis/boundary", "analysis/sensitivity/H_m") of `archive`:
/// `write` fills a fresh group, which then replaces the old product whole (a failure leaves the old
/// one as it was). Throws InputError naming the archive when it cannot be opened for writing
/// (another program reads or writes it; when `printable` names what the caller could print instead,
/// e.g. "the boundary", the error carries remedy "no_write" with that argument: errors.h),
/// ArchiveError for an I/O failure.
void WriteAnalysisProduct(const std::filesystem::path& archive, const std::string& path,
                          const std::string& printable, const std::function<void(ProductGroup&)>& write);

}  // namespace gesweep
