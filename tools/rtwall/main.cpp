#include "commands.h"

#include <rtwall/mesh.h>

#include <cstdio>
#include <exception>
#include <new>

int main(int argc, char** argv) {
    CLI::App app{"rtwall: interactive distributed ray tracing for tiled display walls"};
    app.require_subcommand(1);
    rtwall::cli::Run run;
    rtwall::cli::addRender(app, run);
    rtwall::cli::addInfo(app, run);
    rtwall::cli::addClient(app, run);
    rtwall::cli::addDisplay(app, run);
    rtwall::cli::addRun(app, run);
    rtwall::cli::addControls(app, run);
    rtwall::cli::addKeys(app, run);
    rtwall::cli::addGen(app, run);
    rtwall::cli::addCompare(app, run);
    rtwall::cli::addReference(app, run);
    rtwall::cli::addSimulate(app, run);
    rtwall::cli::addTrackerSim(app, run);
    CLI::App* bench = app.add_subcommand("bench", "Benchmarks that print their figures (JSON with --json)");
    bench->require_subcommand(1);
    rtwall::cli::addBenchKernel(*bench, run);
    rtwall::cli::addBenchCluster(*bench, run);
    rtwall::cli::addBenchFaults(*bench, run);
    rtwall::cli::addBenchAttack(*bench, run);
    rtwall::cli::addBenchChaos(*bench, run);
    rtwall::cli::addBenchUpdates(*bench, run);
    rtwall::cli::addBenchLatency(*bench, run);
    rtwall::cli::addCheck(app, run);
    rtwall::cli::addBenchDisplay(*bench, run);
    rtwall::cli::addBenchScene(*bench, run);
    rtwall::cli::addBenchTiles(*bench, run);
    rtwall::cli::addBenchCodecs(*bench, run);
    rtwall::cli::addBenchShading(*bench, run);
    rtwall::cli::addBenchTessellation(*bench, run);

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
    try {
        return run ? run() : 2;
    } catch (const rtwall::Cancelled&) {
        std::fprintf(stderr, "rtwall: interrupted\n");
        return 130;
    } catch (const rtwall::InputError& e) {
        std::fprintf(stderr, "rtwall: error: %s\n", e.what());
        return 1;
    } catch (const std::bad_alloc&) {
        std::fprintf(stderr, "rtwall: error: out of memory\n");
        return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "rtwall: error: %s\n", e.what());
        return 1;
    }
}
