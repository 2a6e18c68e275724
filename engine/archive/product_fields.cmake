# The layouts of the /analysis products and of the subset-simulation archive, from their one
# description, schemas/products.json, into a C++ header of the build tree (engine/archive/product_fields.h
# below ${GESWEEP_GENERATED_DIR}); schemas/archive.md, "The product layouts", describes the file.
#
# It runs at configure time with CMake's own JSON reader (string(JSON), CMake >= 3.19): no other tool
# is needed to build the engine. The JSON file is a configure dependency, so editing it reconfigures
# and rebuilds what includes the header; the header is rewritten only when its text changes.
#
# For each product (and each of its subgroups, nested) the header declares a namespace
# gesweep::product::<name> with kName, kPath, the namespace `attribute` holding one ProductField per
# attribute, `dataset` one per dataset, a namespace per subgroup, and Layout(), its ProductLayout. A
# field's constant is its name in CamelCase after a k, placeholders unbracketed: "height_m" is
# kHeightM, "<fit>_location" kFitLocation. product::AnalysisProducts() lists the /analysis products in
# the file's order; product::shared::attribute holds the shared attributes.

# `text` as a C++ string literal.
function(_gesweep_cxx_literal out text)
  string(REPLACE "\\" "\\\\" text "${text}")
  string(REPLACE "\"" "\\\"" text "${text}")
  string(REPLACE "\n" "\\n" text "${text}")
  set(${out} "\"${text}\"" PARENT_SCOPE)
endfunction()

# The constant of field `name`: "<fit>_upper_quantiles" -> kFitUpperQuantiles.
function(_gesweep_constant_name out name)
  string(REGEX REPLACE "[^A-Za-z0-9]+" ";" words "${name}")
  set(result "k")
  foreach(word IN LISTS words)
    if(word STREQUAL "")
      continue()
    endif()
    string(SUBSTRING "${word}" 0 1 first)
    string(SUBSTRING "${word}" 1 -1 rest)
    string(TOUPPER "${first}" first)
    string(APPEND result "${first}${rest}")
  endforeach()
  if(result STREQUAL "k")
    message(FATAL_ERROR "${GESWEEP_PRODUCTS_JSON}: the field name '${name}' has no letter or digit")
  endif()
  set(${out} "${result}" PARENT_SCOPE)
endfunction()

# The indices of the JSON array `json`[keys...], a CMake list (empty for an empty array).
function(_gesweep_json_indices out json)
  string(JSON count LENGTH "${json}" ${ARGN})
  set(indices "")
  if(count GREATER 0)
    math(EXPR last "${count} - 1")
    foreach(i RANGE ${last})
      list(APPEND indices ${i})
    endforeach()
  endif()
  set(${out} "${indices}" PARENT_SCOPE)
endfunction()

# Appends `item` to the comma-separated text in variable `var`.
macro(_gesweep_append_listed var item)
  if(NOT "${${var}}" STREQUAL "")
    string(APPEND ${var} ", ")
  endif()
  string(APPEND ${var} "${item}")
endmacro()

# Member `key` of JSON object `json`, which must be there (a missing key names the object).
function(_gesweep_json_get out json where key)
  string(JSON value ERROR_VARIABLE error GET "${json}" ${key})
  if(error)
    message(FATAL_ERROR "${GESWEEP_PRODUCTS_JSON}: ${where} has no '${key}' (${error})")
  endif()
  set(${out} "${value}" PARENT_SCOPE)
endfunction()

# The declarations of the fields of `kind` (attributes or datasets) of layout `json`, at `indent`:
# `out` gets the namespace's text, `out_list` the constants' names, comma-separated.
function(_gesweep_fields out out_list json where kind indent)
  if(kind STREQUAL "attributes")
    set(namespace attribute)
  else()
    set(namespace dataset)
  endif()
  _gesweep_json_indices(indices "${json}" ${kind})
  set(text "")
  set(list "")
  set(seen "")
  if(NOT indices STREQUAL "")
    string(APPEND text "${indent}namespace ${namespace} {\n")
    foreach(i IN LISTS indices)
      string(JSON type TYPE "${json}" ${kind} ${i})
      string(JSON field GET "${json}" ${kind} ${i})
      if(type STREQUAL "STRING")  # one of shared_attributes, by name
        if(NOT DEFINED _gesweep_shared_${field})
          message(FATAL_ERROR "${GESWEEP_PRODUCTS_JSON}: ${where}: '${field}' is not in shared_attributes")
        endif()
        set(field "${_gesweep_shared_${field}}")
      endif()
      _gesweep_json_get(name "${field}" "a field of ${where}" name)
      _gesweep_json_get(field_type "${field}" "${where}: ${name}" type)
      _gesweep_json_get(description "${field}" "${where}: ${name}" description)
      set(units "")
      if(kind STREQUAL "datasets")
        _gesweep_json_get(units "${field}" "${where}: ${name}" units)
      endif()
      _gesweep_json_indices(dimensions "${field}" shape)
      set(shape "")
      foreach(d IN LISTS dimensions)
        string(JSON dimension GET "${field}" shape ${d})
        _gesweep_append_listed(shape "${dimension}")
      endforeach()
      _gesweep_constant_name(constant "${name}")
      if("|${constant}|" IN_LIST seen)
        message(FATAL_ERROR "${GESWEEP_PRODUCTS_JSON}: ${where}: two ${kind} make the constant ${constant}")
      endif()
      list(APPEND seen "|${constant}|")
      foreach(part name field_type units shape description)
        _gesweep_cxx_literal(${part}_literal "${${part}}")
      endforeach()
      string(APPEND text "${indent}inline constexpr ProductField ${constant}{${name_literal}, "
                         "${field_type_literal}, ${units_literal}, ${shape_literal}, ${description_literal}};\n")
      _gesweep_append_listed(list "${namespace}::${constant}")
    endforeach()
    string(APPEND text "${indent}}  // namespace ${namespace}\n")
  endif()
  set(${out} "${text}" PARENT_SCOPE)
  set(${out_list} "${list}" PARENT_SCOPE)
endfunction()

# The namespace of layout `json` (a product or a subgroup) at `indent`, its subgroups nested.
function(_gesweep_layout out json where indent)
  _gesweep_json_get(name "${json}" "${where}" name)
  _gesweep_json_get(path "${json}" "${where} ${name}" path)
  _gesweep_json_get(written_by "${json}" "${where} ${name}" written_by)
  _gesweep_json_get(description "${json}" "${where} ${name}" description)
  if(NOT name MATCHES "^[a-z][a-z0-9_]*$")
    message(FATAL_ERROR "${GESWEEP_PRODUCTS_JSON}: ${where}: the name '${name}' is no C++ namespace name")
  endif()
  set(where "${where} ${name}")
  foreach(part name path written_by description)
    _gesweep_cxx_literal(${part}_literal "${${part}}")
  endforeach()
  set(text "${indent}/// ${description}\n${indent}namespace ${name} {\n")
  string(APPEND text "${indent}inline constexpr const char* kName = ${name_literal};\n")
  string(APPEND text "${indent}/// The group's path (from the root; a subgroup's from its parent).\n")
  string(APPEND text "${indent}inline constexpr const char* kPath = ${path_literal};\n")
  _gesweep_fields(attributes attribute_list "${json}" "${where} attributes" attributes "${indent}")
  _gesweep_fields(datasets dataset_list "${json}" "${where} datasets" datasets "${indent}")
  string(APPEND text "${attributes}${datasets}")
  _gesweep_json_indices(groups "${json}" groups)
  set(group_list "")
  foreach(i IN LISTS groups)
    string(JSON group GET "${json}" groups ${i})
    _gesweep_layout(group_text "${group}" "${where} groups" "${indent}")
    string(JSON group_name GET "${group}" name)
    string(APPEND text "${group_text}")
    _gesweep_append_listed(group_list "${group_name}::Layout()")
  endforeach()
  string(APPEND text "${indent}/// The layout of ${name} (the column manifest's entry).\n"
                     "${indent}inline const ProductLayout& Layout() {\n"
                     "${indent}  static const ProductLayout layout{kName, kPath, ${written_by_literal}, "
                     "${description_literal},\n"
                     "${indent}                                    {${attribute_list}},\n"
                     "${indent}                                    {${dataset_list}},\n"
                     "${indent}                                    {${group_list}}};\n"
                     "${indent}  return layout;\n${indent}}\n")
  string(APPEND text "${indent}}  // namespace ${name}\n\n")
  set(${out} "${text}" PARENT_SCOPE)
endfunction()

# Writes `header` from `json_file`.
function(gesweep_generate_product_fields json_file header)
  if(NOT CMAKE_SCRIPT_MODE_FILE)  # cmake -P: the generator alone, for a look at its output
    set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS "${json_file}")
  endif()
  set(GESWEEP_PRODUCTS_JSON "${json_file}")
  file(READ "${json_file}" json)
  string(JSON shared_count ERROR_VARIABLE error LENGTH "${json}" shared_attributes)
  if(error)
    message(FATAL_ERROR "${json_file}: not the product layouts (${error})")
  endif()
  _gesweep_json_indices(shared "${json}" shared_attributes)
  foreach(i IN LISTS shared)
    string(JSON field GET "${json}" shared_attributes ${i})
    string(JSON name GET "${field}" name)
    set(_gesweep_shared_${name} "${field}")
  endforeach()

  string(CONCAT text "#pragma once\n/// Generated from schemas/products.json by engine/archive/product_fields.cmake when the build is\n"
           "/// configured: do not edit (edit the JSON file). The layout of every /analysis product and of the\n"
           "/// subset-simulation archive: one ProductField constant per attribute and dataset, which the writers\n"
           "/// store through, and each group's ProductLayout, which the column manifest lists.\n\n"
           "#include <vector>\n\n#include \"engine/archive/analysis_product.h\"\n\n"
           "namespace gesweep::product {\n\n")
  string(JSON shared_fields GET "${json}" shared_attributes)
  _gesweep_fields(shared_text shared_list "{\"attributes\": ${shared_fields}}" "shared_attributes" attributes "")
  string(APPEND text "/// The attributes the products record of their writing alike (WriteProvenance).\n"
                     "namespace shared {\n${shared_text}}  // namespace shared\n\n")
  _gesweep_json_indices(products "${json}" products)
  set(product_list "")
  foreach(i IN LISTS products)
    string(JSON product GET "${json}" products ${i})
    _gesweep_layout(product_text "${product}" "products" "")
    string(APPEND text "${product_text}")
    string(JSON product_name GET "${product}" name)
    _gesweep_append_listed(product_list "&${product_name}::Layout()")
  endforeach()
  string(JSON subset ERROR_VARIABLE error GET "${json}" subset_archive)
  if(error)
    message(FATAL_ERROR "${json_file}: no subset_archive (${error})")
  endif()
  _gesweep_layout(subset_text "${subset}" "subset_archive" "")
  string(APPEND text "${subset_text}")
  string(APPEND text "/// The /analysis products, in the order of schemas/products.json (the manifest's).\n"
                     "inline const std::vector<const ProductLayout*>& AnalysisProducts() {\n"
                     "  static const std::vector<const ProductLayout*> products{${product_list}};\n"
                     "  return products;\n}\n\n}  // namespace gesweep::product\n")
  file(WRITE "${header}.new" "${text}")
  configure_file("${header}.new" "${header}" COPYONLY)
  file(REMOVE "${header}.new")
endfunction()
