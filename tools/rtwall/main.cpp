#include "commands.h"

#include <rtwall/mesh.h>

#include <cstdio>
#include <exception>
#include <new>

int main(int argc, char** argv) {
    CLI::App app{"rtwall: interactive distributed ray tracing for tiled display walls"};
    app.require_subcommand(1);
    rtwall::cli::Run run;
    using namespace rtwall::cli;
    // In the order --help lists them.
    for (auto add : {addRender, addInfo, addClient, addDisplay, addRun, addControls, addKeys, addGen, addCompare,
                     addReference, addSimulate, addTrackerSim})
        add(app, run);
    CLI::App* bench = app.add_subcommand("bench", "Benchmarks that print their figures (JSON with --json)");
    bench->require_subcommand(1);
    for (auto add : {addBenchKernel, addBenchCluster, addBenchFaults, addBenchAttack, addBenchChaos, addBenchUpdates, addBenchWeb,
                     addBenchLatency, addBenchDisplay, addBenchScene, addBenchTiles, addBenchCodecs, addBenchShading,
                     addBenchTessellation, addBenchWarp})
        add(*bench, run);
    addBenchReproject(*bench, run);
    addBenchDenoise(*bench, run);
    addCheck(app, run);

    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        // One line, exit status 2, for every command-line mistake.
        std::fprintf(stderr, "rtwall: error: %s (see 'rtwall --help')\n", e.what());
        return 2;
    }
    // Whatever a command throws is one line and exit status 1 (130 when interrupted).
    const auto fail = [](const char* what) {
        std::fprintf(stderr, "rtwall: error: %s\n", what);
        return 1;
    };
    try {
        return run ? run() : 2;
    } catch (const rtwall::Cancelled&) {
        std::fprintf(stderr, "rtwall: interrupted\n");
        return 130;
    } catch (const std::bad_alloc&) {
        return fail("out of memory");
    } catch (const std::exception& e) {  // an InputError too: its message names the file and line
        return fail(e.what());
    }
}
