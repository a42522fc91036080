#ifndef SPINESIM_BASE_REGISTRY_H
#define SPINESIM_BASE_REGISTRY_H

// ASPECT-style registry: models register themselves by name with a description, their
// parameter declarations and a factory. The list of valid names, their documentation and
// the parameter pattern all come from here, never from a hand-kept if/else chain.
// `Entry` is any struct with `name` and `description` members.

#include "base/exceptions.h"

#include <map>
#include <string>

namespace spinesim {

template <typename Entry>
class Registry {
 public:
  static Registry& instance() {
    static Registry registry;
    return registry;
  }

  bool add(Entry entry) {
    const std::string name = entry.name;
    return entries_.emplace(name, std::move(entry)).second;
  }

  // `where` names the parameter that selected the name, for the error message.
  const Entry& get(const std::string& name, const std::string& where) const {
    const auto it = entries_.find(name);
    if (it == entries_.end())
      throw InvalidInput(where, "unknown name '" + name + "'", names("|"));
    return it->second;
  }

  std::string names(const std::string& separator) const {
    std::string out;
    for (const auto& [name, entry] : entries_)
      out += (out.empty() ? "" : separator) + name;
    return out;
  }

  // "'name': description" for every entry, for help texts.
  std::string documentation() const {
    std::string out;
    for (const auto& [name, entry] : entries_)
      out += "'" + name + "': " + entry.description + " ";
    return out;
  }

  const std::map<std::string, Entry>& entries() const { return entries_; }

 private:
  std::map<std::string, Entry> entries_;
};

} // namespace spinesim

#endif
