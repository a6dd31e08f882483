// Strict reading of TOML configuration files (scene files, run configs): every table is read
// through a Reader that records which keys were used, so a typo such as `colour = [...]` is
// reported with its file and line instead of being silently ignored; wrong types, out-of-range
// and non-finite numbers are errors too. Every error is an InputError of one line:
// "<file>:<line>: <context><what>".
//
// A parser describes each section ([render], [[screen]], ...) by a table of Keys: name, type,
// accepted range or choices, and the help text configs/README.md gives for it. A Reader given
// such a Section takes every range and choice list from it, and reading a key the table does not
// list is a programming error (std::logic_error), so the tables name every key a file may hold;
// a test holds them against configs/README.md (undocumentedKeys below).
#pragma once

#include <rtwall/input_error.h>
#include <rtwall/vec.h>

#include <toml++/toml.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <optional>
#include <set>
#include <span>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <variant>
#include <vector>

namespace rtwall::toml_reader {

// What a key holds, as the documentation's "type" column says it.
enum class KeyType {
    Number,     // an integer or a float in [lo, hi]
    Integer,    // an integer in [lo, hi]
    Boolean,
    String,
    Choice,     // one of the strings in `choices`
    Vec3,       // [x, y, z], single precision
    Vec3d,      // [x, y, z], double precision
    Integers,   // an array of integers, each in [lo, hi]
    Numbers,    // a number or an array of numbers, each in [lo, hi]
    Scale,      // a number in [lo, hi] or [x, y, z]
    Strings,    // an array of strings
    Points,     // an array of arrays of numbers
    Table,      // [name]
    Tables,     // [[name]]
};

// One key of a section.
struct Key {
    std::string_view name;
    KeyType type;
    double lo = 0, hi = 0;          // Number, Integer, Integers, Numbers, Scale
    std::string_view choices = {};  // Choice: "a, b, c", as error messages list them
    std::string_view help = {};     // what configs/README.md says about the key
};

// A section of a file and the keys it may hold. `doc` is the heading under which
// configs/README.md documents it.
struct Section {
    std::string_view name;
    std::string_view doc;
    std::span<const Key> keys;

    const Key* find(std::string_view key) const {
        for (const Key& k : keys)
            if (k.name == key) return &k;
        return nullptr;
    }
};

inline std::string where(const std::filesystem::path& file, const toml::source_region& src) {
    std::string s = file.string();
    if (src.begin.line > 0) s += ":" + std::to_string(src.begin.line);
    return s;
}

class Reader {
public:
    Reader(const std::filesystem::path& file, const toml::table& table, std::string context)
        : file_(file), table_(table), context_(std::move(context)) {}
    Reader(const std::filesystem::path& file, const toml::table& table, std::string context, const Section& section)
        : file_(file), table_(table), context_(std::move(context)), sections_{&section} {}

    // Keys of a part of the section that depends on another key (a shape's parameters): looked
    // up before the section's own, so a key may have another range there.
    void extend(const Section& part) { sections_.insert(sections_.begin(), &part); }

    // The table's entry for `key`, which must be of type `type`.
    const Key& spec(const std::string& key, KeyType type) const {
        for (const Section* s : sections_)
            if (const Key* k = s->find(key)) {
                if (k->type != type)
                    throw std::logic_error("rtwall: key '" + key + "' of " + std::string(s->name) + " is read as another type than its table says");
                return *k;
            }
        throw std::logic_error("rtwall: key '" + key + "' is read but is not in its section's table");
    }

    [[noreturn]] void fail(const toml::node* node, const std::string& what) const {
        const toml::source_region& src = node ? node->source() : table_.source();
        throw InputError(where(file_, src) + ": " + context_ + what);
    }

    const toml::node* find(const std::string& key) {
        listed(key);
        used_.insert(key);
        return table_.get(key);
    }

    bool has(const std::string& key) const {
        listed(key);
        return table_.contains(key);
    }

    // The range and the choices from the section's table.
    double number(const std::string& key, double def) {
        const Key& k = spec(key, KeyType::Number);
        return number(key, def, k.lo, k.hi);
    }
    int integer(const std::string& key, int def) {
        const Key& k = spec(key, KeyType::Integer);
        return integer(key, def, int(k.lo), int(k.hi));
    }
    std::string choice(const std::string& key, const std::string& def) {
        const std::string_view choices = spec(key, KeyType::Choice).choices;
        const std::string v = string(key, def);
        for (size_t begin = 0; begin < choices.size();) {
            const size_t end = std::min(choices.find(", ", begin), choices.size());
            if (choices.substr(begin, end - begin) == v) return v;
            begin = end + 2;
        }
        fail(find(key), "key '" + key + "': '" + v + "' is not one of " + std::string(choices));
    }

    double number(const std::string& key, double def, double lo, double hi) {
        const toml::node* n = find(key);
        if (!n) return def;
        double v;
        if (auto i = n->as_integer()) v = double(i->get());
        else if (auto f = n->as_floating_point()) v = f->get();
        else fail(n, "key '" + key + "': expected a number, got " + typeName(*n));
        if (!std::isfinite(v)) fail(n, "key '" + key + "': value must be finite");
        if (v < lo || v > hi) {
            std::ostringstream os;
            os << "key '" << key << "': " << v << " is out of range [" << lo << ", " << hi << "]";
            fail(n, os.str());
        }
        return v;
    }

    int integer(const std::string& key, int def, int lo, int hi) {
        const toml::node* n = find(key);
        if (!n) return def;
        auto i = n->as_integer();
        if (!i) fail(n, "key '" + key + "': expected an integer, got " + typeName(*n));
        const int64_t v = i->get();
        if (v < lo || v > hi)
            fail(n, "key '" + key + "': " + std::to_string(v) + " is out of range [" + std::to_string(lo) + ", " +
                        std::to_string(hi) + "]");
        return int(v);
    }

    bool boolean(const std::string& key, bool def) {
        const toml::node* n = find(key);
        if (!n) return def;
        auto b = n->as_boolean();
        if (!b) fail(n, "key '" + key + "': expected true or false, got " + typeName(*n));
        return b->get();
    }

    std::string string(const std::string& key, const std::string& def, bool required = false) {
        const toml::node* n = find(key);
        if (!n) {
            if (required) fail(nullptr, "missing required key '" + key + "'");
            return def;
        }
        auto s = n->as_string();
        if (!s) fail(n, "key '" + key + "': expected a string, got " + typeName(*n));
        return s->get();
    }

    std::string choice(const std::string& key, const std::string& def, std::initializer_list<const char*> options) {
        const std::string v = string(key, def);
        std::string list;
        for (const char* o : options) {
            if (v == o) return v;
            list += std::string(list.empty() ? "" : ", ") + o;
        }
        fail(find(key), "key '" + key + "': '" + v + "' is not one of " + list);
    }

    Float3 vec3(const std::string& key, Float3 def, bool required = false) {
        const std::optional<std::array<double, 3>> v = triple(key, required, 1e30, "");
        return v ? Float3{float((*v)[0]), float((*v)[1]), float((*v)[2])} : def;
    }

    // An [x, y, z] in double precision (world placements, CAD coordinates): within 1e15.
    std::array<double, 3> vec3d(const std::string& key, std::array<double, 3> def, bool required = false) {
        return triple(key, required, 1e15, " and within 1e15").value_or(def);
    }

    // Reports the first key that was never read: a typo or a key in the wrong table.
    void finish() const {
        for (const auto& [k, node] : table_)
            if (!used_.count(std::string(k.str())))
                throw InputError(where(file_, k.source().begin.line ? k.source() : node.source()) + ": " + context_ +
                                 "unknown key '" + std::string(k.str()) + "'");
    }

    static std::string typeName(const toml::node& n) {
        switch (n.type()) {
        case toml::node_type::table: return "a table";
        case toml::node_type::array: return "an array";
        case toml::node_type::string: return "a string";
        case toml::node_type::integer: return "an integer";
        case toml::node_type::floating_point: return "a float";
        case toml::node_type::boolean: return "a boolean";
        default: return "a date/time";
        }
    }

private:
    // The numbers of key's [x, y, z], each finite and within `limit` (`within` says so in the
    // error); nothing when the key is absent (an error if `required`).
    std::optional<std::array<double, 3>> triple(const std::string& key, bool required, double limit, const char* within) {
        const toml::node* n = find(key);
        if (!n) {
            if (required) fail(nullptr, "missing required key '" + key + "'");
            return std::nullopt;
        }
        auto a = n->as_array();
        if (!a || a->size() != 3) fail(n, "key '" + key + "': expected an array of 3 numbers");
        std::array<double, 3> v{};
        for (size_t i = 0; i < 3; ++i) {
            const toml::node& e = *a->get(i);
            if (auto x = e.as_integer()) v[i] = double(x->get());
            else if (auto f = e.as_floating_point()) v[i] = f->get();
            else fail(n, "key '" + key + "': element " + std::to_string(i) + " is " + typeName(e) + ", not a number");
            if (!std::isfinite(v[i]) || std::fabs(v[i]) > limit)
                fail(n, "key '" + key + "': element " + std::to_string(i) + " must be finite" + within);
        }
        return v;
    }

    void listed(const std::string& key) const {
        if (sections_.empty()) return;
        for (const Section* s : sections_)
            if (s->find(key)) return;
        throw std::logic_error("rtwall: key '" + key + "' of " + std::string(sections_.back()->name) +
                               " is read but is not in its table");
    }

    const std::filesystem::path& file_;
    const toml::table& table_;
    std::string context_;
    std::vector<const Section*> sections_;  // empty: any key may be read
    std::set<std::string> used_;
};

// A key read straight into a member of T: integer, number (double or float), boolean, [x, y, z]
// or string, with the range its section's table gives.
template <class T>
struct Field {
    const char* key;
    std::variant<int T::*, double T::*, float T::*, bool T::*, Float3 T::*, std::string T::*> member;
};

// Reads the fields in their order, each defaulting to what the member holds.
template <class T>
void readFields(Reader& r, T& object, std::initializer_list<Field<T>> fields) {
    for (const Field<T>& f : fields)
        std::visit(
            [&](auto member) {
                auto& value = object.*member;
                using V = std::remove_reference_t<decltype(value)>;
                if constexpr (std::is_same_v<V, int>) value = r.integer(f.key, value);
                else if constexpr (std::is_same_v<V, double>) value = r.number(f.key, value);
                else if constexpr (std::is_same_v<V, float>) value = float(r.number(f.key, value));
                else if constexpr (std::is_same_v<V, bool>) value = r.boolean(f.key, value);
                else if constexpr (std::is_same_v<V, Float3>) value = r.vec3(f.key, value);
                else value = r.string(f.key, value);
            },
            f.member);
}

// Visits [[name]] (an array of tables) or reports what is there instead. With a section, each
// entry's Reader checks its keys against it.
template <class F>
void forEachTable(Reader& top, const std::filesystem::path& file, const std::string& name, F&& f,
                  const Section* section = nullptr) {
    const toml::node* n = top.find(name);
    if (!n) return;
    const toml::array* arr = n->as_array();
    if (!arr) top.fail(n, "'" + name + "' must be an array of tables, written [[" + name + "]]");
    size_t index = 0;
    for (const toml::node& e : *arr) {
        const toml::table* t = e.as_table();
        if (!t) top.fail(&e, "'" + name + "' entries must be tables, written [[" + name + "]]");
        const std::string context = "[[" + name + "]] #" + std::to_string(index + 1) + ": ";
        Reader r = section ? Reader(file, *t, context, *section) : Reader(file, *t, context);
        f(r, *t);
        r.finish();
        ++index;
    }
}

template <class F>
void forEachTable(Reader& top, const std::filesystem::path& file, const Section& section, F&& f) {
    const std::string_view name = section.name;  // "[[name]]"
    forEachTable(top, file, std::string(name.substr(2, name.size() - 4)), std::forward<F>(f), &section);
}

inline const toml::table* subTable(Reader& top, const std::string& name) {
    const toml::node* n = top.find(name);
    if (!n) return nullptr;
    const toml::table* t = n->as_table();
    if (!t) top.fail(n, "'" + name + "' must be a table, written [" + name + "]");
    return t;
}

// The Reader of [name] when the file has it.
inline std::optional<Reader> sectionReader(Reader& top, const std::filesystem::path& file, const Section& section) {
    const std::string_view name = section.name;  // "[name]"
    const toml::table* t = subTable(top, std::string(name.substr(1, name.size() - 2)));
    if (!t) return std::nullopt;
    return std::optional<Reader>(std::in_place, file, *t, std::string(name) + ": ", section);
}

// The keys of `sections` that `doc` (configs/README.md) does not document under the section's
// heading, as "section key" lines, and keys whose help is not the documentation's text. A key is
// documented as `key` in a table row or as `key = ` in an example; a key that is itself a table
// as `[key]` or `[[key]]` anywhere (an inline table also as `key` in its section).
inline std::vector<std::string> undocumentedKeys(std::span<const Section* const> sections, const std::string& doc) {
    std::vector<std::string> out;
    for (const Section* s : sections) {
        size_t begin = std::string::npos;
        for (size_t at = 0; (at = doc.find(std::string(s->doc), at)) != std::string::npos; ++at)
            if (at == 0 || doc[at - 1] == '\n') {
                begin = at;
                break;
            }
        if (begin == std::string::npos) {
            out.push_back(std::string(s->name) + ": no heading '" + std::string(s->doc) + "'");
            continue;
        }
        size_t end = doc.find("\n#", begin + 1);
        const std::string text = doc.substr(begin, end == std::string::npos ? std::string::npos : end - begin);
        for (const Key& k : s->keys) {
            const std::string name(k.name);
            const bool documented =
                k.type == KeyType::Table    ? doc.find("[" + name + "]") != std::string::npos ||
                                                  text.find("`" + name + "`") != std::string::npos  // an inline table
                : k.type == KeyType::Tables ? doc.find("[[" + name + "]]") != std::string::npos
                                            : text.find("`" + name + "`") != std::string::npos ||
                                                  text.find("\n" + name + " = ") != std::string::npos;
            if (!documented) out.push_back(std::string(s->name) + " " + name);
            else if (!k.help.empty() && text.find(std::string(k.help)) == std::string::npos)
                out.push_back(std::string(s->name) + " " + name + ": help differs from the documentation");
        }
    }
    return out;
}

// The same for the documentation in `docFile`.
inline std::vector<std::string> undocumentedKeys(std::span<const Section* const> sections, const std::filesystem::path& docFile) {
    std::ifstream in(docFile);
    std::stringstream doc;
    doc << in.rdbuf();
    if (!in || doc.str().empty()) return {docFile.string() + ": cannot read it"};
    return undocumentedKeys(sections, doc.str());
}

// Parses a file, turning toml++'s parse errors into one-line InputErrors.
inline toml::table parseFile(const std::filesystem::path& file) {
    if (!std::filesystem::exists(file)) throw InputError(file.string() + ": no such file");
    try {
        return toml::parse_file(file.string());
    } catch (const toml::parse_error& e) {
        throw InputError(where(file, e.source()) + ": " + std::string(e.description()));
    }
}

}  // namespace rtwall::toml_reader
