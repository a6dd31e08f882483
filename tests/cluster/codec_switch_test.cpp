// Master::setCodec on a running cluster: the operating-point controller of `rtwall run
// --target-fps` changes the codec between frames. Loopback only, client threads.
#include "test_util.h"

#include <rtwall/cluster.h>
#include <rtwall/tune.h>

#include <gtest/gtest.h>

#include <thread>

namespace rtwall {
namespace {

TEST(CodecSwitch, TheNextFrameUsesTheNewCodecAndLosslessIsExactAgain) {
    SceneDesc desc = loadSceneFile(test::sourceDir() / "configs/demo.toml");
    desc.settings.width = 192;
    desc.settings.height = 128;
    desc.settings.supersample = 1;
    desc.settings.tileSize = 32;
    const Scene scene(desc);
    const Image reference = renderFrame(scene, Camera(desc.cameras.front(), 192, 128), desc.settings);

    ClusterSettings cs;
    cs.codec.codec = TileCodec::Lz4;
    cs.async = false;
    std::vector<std::thread> clients;
    {
        Master master(desc, cs);
        for (int i = 0; i < 2; ++i) {
            ClientSettings c;
            c.connect = master.endpoint();
            c.threads = 1;
            c.exitAfterIdleMs = 4000;
            clients.emplace_back([c] { runClient(c); });
        }
        ASSERT_TRUE(master.waitForClients(2, 30'000));
        FrameReport lz4;
        EXPECT_EQ(master.renderFrame(&lz4).rgb, reference.rgb);

        master.setCodec({TileCodec::Jpeg, 30, true, 1});
        FrameReport jpeg;
        const Image lossy = master.renderFrame(&jpeg);
        const ImageError e = compareImages(lossy, reference);
        EXPECT_FALSE(e.identical());
        EXPECT_GT(e.psnrDb, 25.0);
        EXPECT_NE(jpeg.bytes, lz4.bytes);

        master.setCodec({TileCodec::Lz4, 90, false, 1});
        FrameReport back;
        EXPECT_EQ(master.renderFrame(&back).rgb, reference.rgb);
        EXPECT_EQ(back.bytes, lz4.bytes);
    }
    for (auto& t : clients) t.join();
}

}  // namespace
}  // namespace rtwall
