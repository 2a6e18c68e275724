#pragma once
/// The archive's layout beyond the columns, as the column manifest lists it (`gesweep columns --json`;
/// schemas/archive.md, "The column manifest") and the Python module carries it (gesweep._gesweep.
/// _archive_layout): the archive's groups, the bookkeeping datasets under runs/, the run-status levels,
/// every /analysis product and the subset-simulation archive, each from the description its writer
/// stores (the ProductLayouts generated from schemas/products.json, engine/archive/product_fields.h;
/// RunStatus's names table). The Python reader of archives
/// (engine/python/gesweep/_hdf5.py) finds every path there and spells none.

#include <nlohmann/json.hpp>

namespace gesweep {

/// {"groups", "runs", "run_status", "products", "subset_archive"}: the keys the manifest carries.
nlohmann::ordered_json ArchiveLayoutJson();

}  // namespace gesweep
