// rtwall gen NAME --out DIR: the scene generators (tools/gen/).
#include "commands.h"

#include <generators.h>

#include <rtwall/mesh.h>

#include <chrono>
#include <cstdio>
#include <memory>

namespace rtwall::cli {

void addGen(CLI::App& app, Run& run) {
    auto o = std::make_shared<gen::GenOptions>();
    auto name = std::make_shared<std::string>();
    CLI::App* cmd = app.add_subcommand("gen", "Generate a test or benchmark scene: mesh files plus scene.toml");
    // The CAD generators and the shading demos (tools/gen/), one list.
    const std::map<std::string, gen::Generator>& all = gen::generators();
    std::string list;
    std::vector<std::string> names;
    for (const auto& [n, g] : all) {
        list += "\n  " + n + ": " + g.help;
        names.push_back(n);
    }
    cmd->add_option("generator", *name, "Which scene:" + list)->required()->check(CLI::IsMember(names));
    cmd->add_option("--out,-o", o->out, "Output directory (created)")->required();
    cmd->add_option("--triangles", o->triangles, "Size: powerplant: unique triangles (12.5M); sunflowers: per plant (36,000)")
        ->check(CLI::Range(int64_t(100), int64_t(2'000'000'000)));
    cmd->add_option("--instances", o->instances, "sunflowers: plants (28,000); step: part instances (7,000)")->check(CLI::Range(int64_t(1), int64_t(10'000'000)));
    cmd->add_option("--copies", o->copies, "powerplant: plants side by side (1)")->check(CLI::Range(1, 64));
    cmd->add_option("--trees", o->trees, "sunflowers: large trees (4)")->check(CLI::Range(0, 64));
    cmd->add_option("--tree-triangles", o->treeTriangles, "sunflowers: triangles per tree (2.5M)")
        ->check(CLI::Range(int64_t(100), int64_t(100'000'000)));
    cmd->add_option("--seed", o->seed, "Random seed (same seed, same files)");
    cmd->add_flag("--flat", o->flat,
                  "step, iges: a flat file: every part a solid of its own placed in its geometry (no assembly reuse), and "
                  "one mirrored bracket");
    cmd->add_flag("--rows", o->rows, "step, step-curved, iges: plant > row sub-assemblies > modules (nested, as large CAD assemblies are)");
    cmd->add_option("--unit", o->stepUnit, "step, step-curved: the file's length unit (MM, M, CM, INCH, FT, ...; MM)")
        ->check(CLI::IsMember({"MM", "M", "CM", "KM", "UM", "INCH", "FT", "MI", "MIL"}));
    cmd->add_flag("!--no-cache", o->cache, "Write [load] cache = false into the scene");
    cmd->callback([&run, o, name] {
        run = [o, name] {
            const auto t0 = std::chrono::steady_clock::now();
            try {
                gen::generators().at(*name).run(*o);
            } catch (const std::filesystem::filesystem_error& e) {
                throw InputError(std::string("gen: ") + e.what());
            } catch (const std::runtime_error& e) {
                throw InputError(std::string("gen: ") + e.what());
            }
            std::fprintf(stderr, "rtwall gen %s: wrote %s in %.1f s\n", name->c_str(), o->out.c_str(),
                         std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
            return 0;
        };
    });
}

}  // namespace rtwall::cli
