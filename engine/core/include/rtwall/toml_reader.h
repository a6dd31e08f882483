// Strict reading of TOML configuration files (scene files, run configs): every table is read
// through a Reader that records which keys were used, so a typo such as `colour = [...]` is
// reported with its file and line instead of being silently ignored; wrong types, out-of-range
// and non-finite numbers are errors too. Every error is an InputError of one line:
// "<file>:<line>: <context><what>".
#pragma once

#include <rtwall/input_error.h>
#include <rtwall/vec.h>

#include <toml++/toml.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <initializer_list>
#include <set>
#include <sstream>
#include <string>

namespace rtwall::toml_reader {

inline std::string where(const std::filesystem::path& file, const toml::source_region& src) {
    std::string s = file.string();
    if (src.begin.line > 0) s += ":" + std::to_string(src.begin.line);
    return s;
}

class Reader {
public:
    Reader(const std::filesystem::path& file, const toml::table& table, std::string context)
        : file_(file), table_(table), context_(std::move(context)) {}

    [[noreturn]] void fail(const toml::node* node, const std::string& what) const {
        const toml::source_region& src = node ? node->source() : table_.source();
        throw InputError(where(file_, src) + ": " + context_ + what);
    }

    const toml::node* find(const std::string& key) {
        used_.insert(key);
        return table_.get(key);
    }

    bool has(const std::string& key) const { return table_.contains(key); }

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
        const toml::node* n = find(key);
        if (!n) {
            if (required) fail(nullptr, "missing required key '" + key + "'");
            return def;
        }
        auto a = n->as_array();
        if (!a || a->size() != 3) fail(n, "key '" + key + "': expected an array of 3 numbers");
        float v[3];
        for (size_t i = 0; i < 3; ++i) {
            const toml::node& e = *a->get(i);
            double d;
            if (auto x = e.as_integer()) d = double(x->get());
            else if (auto f = e.as_floating_point()) d = f->get();
            else fail(n, "key '" + key + "': element " + std::to_string(i) + " is " + typeName(e) + ", not a number");
            if (!std::isfinite(d) || std::fabs(d) > 1e30)
                fail(n, "key '" + key + "': element " + std::to_string(i) + " must be finite");
            v[i] = float(d);
        }
        return {v[0], v[1], v[2]};
    }

    // An [x, y, z] in double precision (world placements, CAD coordinates): within 1e15.
    std::array<double, 3> vec3d(const std::string& key, std::array<double, 3> def, bool required = false) {
        const toml::node* n = find(key);
        if (!n) {
            if (required) fail(nullptr, "missing required key '" + key + "'");
            return def;
        }
        auto a = n->as_array();
        if (!a || a->size() != 3) fail(n, "key '" + key + "': expected an array of 3 numbers");
        std::array<double, 3> v{};
        for (size_t i = 0; i < 3; ++i) {
            const toml::node& e = *a->get(i);
            if (auto x = e.as_integer()) v[i] = double(x->get());
            else if (auto f = e.as_floating_point()) v[i] = f->get();
            else fail(n, "key '" + key + "': element " + std::to_string(i) + " is " + typeName(e) + ", not a number");
            if (!std::isfinite(v[i]) || std::fabs(v[i]) > 1e15)
                fail(n, "key '" + key + "': element " + std::to_string(i) + " must be finite and within 1e15");
        }
        return v;
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
    const std::filesystem::path& file_;
    const toml::table& table_;
    std::string context_;
    std::set<std::string> used_;
};

// Visits [[name]] (an array of tables) or reports what is there instead.
template <class F>
void forEachTable(Reader& top, const std::filesystem::path& file, const std::string& name, F&& f) {
    const toml::node* n = top.find(name);
    if (!n) return;
    const toml::array* arr = n->as_array();
    if (!arr) top.fail(n, "'" + name + "' must be an array of tables, written [[" + name + "]]");
    size_t index = 0;
    for (const toml::node& e : *arr) {
        const toml::table* t = e.as_table();
        if (!t) top.fail(&e, "'" + name + "' entries must be tables, written [[" + name + "]]");
        Reader r(file, *t, "[[" + name + "]] #" + std::to_string(index + 1) + ": ");
        f(r, *t);
        r.finish();
        ++index;
    }
}

inline const toml::table* subTable(Reader& top, const std::string& name) {
    const toml::node* n = top.find(name);
    if (!n) return nullptr;
    const toml::table* t = n->as_table();
    if (!t) top.fail(n, "'" + name + "' must be a table, written [" + name + "]");
    return t;
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
