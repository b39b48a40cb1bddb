// Camera images of a solution: every pixel of the EXR, read back with
// OpenEXR, is the radiance B / pi of the patch it sees (scene-referred: the
// exposure is an attribute for viewers), and the EXR says what its RGB
// means; the luminance image is 179 lm/W times its luminance, in cd/m2.
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFloatAttribute.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfStandardAttributes.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "color.h"
#include "image_writer.h"
#include "render.h"
#include "test_util.h"

namespace mpath {
namespace {

using test::TempDir;

struct ExrImage {
  int width = 0, height = 0;
  std::vector<float> r, g, b;
  float exposure = 0;
  std::string units;
};

ExrImage read_exr(const std::filesystem::path& path) {
  Imf::InputFile file(path.c_str());
  const Imath::Box2i dw = file.header().dataWindow();
  ExrImage img;
  img.width = dw.max.x - dw.min.x + 1;
  img.height = dw.max.y - dw.min.y + 1;
  for (auto* v : {&img.r, &img.g, &img.b}) v->resize(static_cast<size_t>(img.width) * img.height);
  Imf::FrameBuffer fb;
  const size_t xs = sizeof(float), ys = xs * img.width;
  fb.insert("R", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(img.r.data()), xs, ys));
  fb.insert("G", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(img.g.data()), xs, ys));
  fb.insert("B", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(img.b.data()), xs, ys));
  file.setFrameBuffer(fb);
  file.readPixels(dw.min.y, dw.max.y);
  img.exposure = file.header().typedAttribute<Imf::FloatAttribute>("exposure").value();
  img.units = file.header().typedAttribute<Imf::StringAttribute>("mpathUnits").value();
  return img;
}

// A closed 4 x 3 x 2.5 room, each wall one polygon and one patch (so the
// radiosity interpolated over a patch is the patch's own), with a radiosity
// of its own per wall and channel.
TEST(Render, ExrPixelsAreTheRadianceOfThePatchSeen) {
  Scene scene;
  const int grey = test::add_material(scene, "wall", 0.5, 1.0);
  test::add_box(scene, {0, 0, 0}, {4, 3, 2.5}, true, grey, test::add_object(scene, "room"));
  scene.materials[grey].rho = {0.5, 0.4, 0.3};  // three channels
  const PatchMesh mesh = build_mesh(scene, 100.0);
  ASSERT_EQ(mesh.face_count(), 6u);
  RadiosityState state = make_state(scene, mesh);
  ASSERT_EQ(state.channels, 3);
  std::vector<std::array<double, 3>> radiosity(6);
  for (size_t f = 0; f < 6; ++f)
    for (int c = 0; c < 3; ++c) {
      radiosity[f][c] = 1.0 + f + 0.25 * c;
      state.phi[state.at(f, c)] = radiosity[f][c] * mesh.face_area(static_cast<int>(f));
    }
  const Tracer tracer(mesh);
  CameraOptions cam;
  cam.position = {2, 1.5, 1.25};
  cam.look_at = {4, 1.5, 1.25};  // the +x wall, straight ahead
  cam.up = {0, 0, 1};
  cam.fov_deg = 90;
  cam.width = 33;
  cam.height = 21;
  cam.samples = 1;
  cam.exposure = 1.5;
  const Image image = render_camera(cam, mesh, tracer, VertexRadiosity(mesh, state), 1);
  TempDir dir;
  write_exr(dir / "room.exr", image, cam.exposure, {{"mpathUnits", "radiance W/sr/m2"}});
  const ExrImage back = read_exr(dir / "room.exr");
  ASSERT_EQ(back.width, cam.width);
  ASSERT_EQ(back.height, cam.height);
  EXPECT_FLOAT_EQ(back.exposure, 1.5f);
  EXPECT_EQ(back.units, "radiance W/sr/m2");
  {
    Imf::InputFile file((dir / "room.exr").c_str());
    ASSERT_TRUE(Imf::hasChromaticities(file.header()));
    const Imf::Chromaticities c = Imf::chromaticities(file.header());
    EXPECT_FLOAT_EQ(c.red.x, 0.64f);
    EXPECT_FLOAT_EQ(c.green.y, 0.60f);
    EXPECT_FLOAT_EQ(c.white.x, 1 / 3.f);  // equal-energy white, not D65
    ASSERT_TRUE(Imf::hasWhiteLuminance(file.header()));
    EXPECT_FLOAT_EQ(Imf::whiteLuminance(file.header()), 179.f);
  }
  write_scalar_exr(dir / "room.luminance.exr", image.width, image.height, luminance_cd_m2(image), {});
  std::vector<float> y(static_cast<size_t>(image.width) * image.height);
  {
    Imf::InputFile file((dir / "room.luminance.exr").c_str());
    Imf::FrameBuffer fb;
    fb.insert("Y", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(y.data()), sizeof(float), sizeof(float) * image.width));
    file.setFrameBuffer(fb);
    file.readPixels(0, image.height - 1);
  }
  // The face straight ahead, found as the renderer does: one ray through the centre.
  const NearestHit hit = tracer.nearest(cam.position, {1, 0, 0}, 0.0, 100.0);
  ASSERT_GE(hit.patch, 0);
  const int face = mesh.patch_faces[hit.patch][0];
  ASSERT_GE(face, 0);
  const size_t centre = static_cast<size_t>(cam.height / 2) * cam.width + cam.width / 2;
  const double scale = 1 / std::numbers::pi;
  const Rgb seen{radiosity[face][0] * scale, radiosity[face][1] * scale, radiosity[face][2] * scale};
  EXPECT_NEAR(y[centre], 179 * luminance(seen), 1e-5 * 179 * luminance(seen));
  EXPECT_NEAR(back.r[centre], radiosity[face][0] * scale, 1e-5 * radiosity[face][0] * scale);
  EXPECT_NEAR(back.g[centre], radiosity[face][1] * scale, 1e-5 * radiosity[face][1] * scale);
  EXPECT_NEAR(back.b[centre], radiosity[face][2] * scale, 1e-5 * radiosity[face][2] * scale);
  // Every pixel shows one of the walls' radiances: nothing is blended across walls.
  for (size_t i = 0; i < back.r.size(); ++i) {
    bool some_wall = false;
    for (const auto& b : radiosity) some_wall |= std::abs(back.r[i] - b[0] * scale) < 1e-5 * b[0] * scale;
    EXPECT_TRUE(some_wall) << "pixel " << i << " = " << back.r[i];
  }
}

}  // namespace
}  // namespace mpath
