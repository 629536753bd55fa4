#pragma once
// A wire struct as JSON, from its field list (field_list.hpp): every field by its name, in
// the listed order; nested structs as objects, vectors as arrays, enums by their names.
// What `robodiff health --json` and the dashboard's /api/overview print of a message.

#include <nlohmann/json.hpp>
#include <string>
#include <type_traits>
#include <vector>

#include "robodiff/schema/messages.hpp"

namespace robodiff::rpc {

template <class T>
nlohmann::ordered_json messageJson(const T& value);

namespace json_detail {
template <class T>
struct IsVector : std::false_type {};
template <class T>
struct IsVector<std::vector<T>> : std::true_type {};
}  // namespace json_detail

template <class T>
nlohmann::ordered_json messageJson(const T& value) {
  if constexpr (HasFields<T>) {
    nlohmann::ordered_json object = nlohmann::ordered_json::object();
    Fields<T>::visit(value, value, [&](const char* name, const auto& field, const auto&) {
      object[name] = messageJson(field);
    });
    return object;
  } else if constexpr (json_detail::IsVector<T>::value) {
    nlohmann::ordered_json array = nlohmann::ordered_json::array();
    for (const auto& element : value) array.push_back(messageJson(element));
    return array;
  } else if constexpr (std::is_enum_v<T>) {
    return toString(value);
  } else {
    return value;  // strings, numbers, booleans
  }
}

}  // namespace robodiff::rpc
