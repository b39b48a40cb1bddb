// mpath-compare: error of a radiosity solution against a reference solution.
#include "compare.h"
#include "process_memory.h"
#include "program.h"

int main(int argc, char** argv) {
  mpath::use_huge_pages(argv);  // first: it may run the program again in place
  CLI::App app{"mpath-compare: error of a solution against a reference on the same mesh, with error images", "mpath-compare"};
  mpath::ProgramFlags flags;
  mpath::CompareFlags compare;
  bool no_images = false;
  std::string result, reference, out;
  app.add_option("--result", result, "solution.ply (or the output.dir holding it) to measure")->required();
  app.add_option("--reference", reference, "reference solution.ply (or its output.dir)")->required();
  app.add_option("--out", out, "directory for compare.json and the error images (default: RESULT/compare)");
  app.add_option("--scale", compare.scale, "relative error at the top of the image colour map (default 0.2)")
      ->check(CLI::PositiveNumber);
  app.add_flag("--no-images", no_images, "numbers only");
  mpath::add_common_flags(app, flags);
  if (const int status = mpath::parse_command_line(app, argc, argv); status >= 0) return status;
  compare.result = result;
  compare.reference = reference;
  compare.images = !no_images;
  const std::filesystem::path base = std::filesystem::is_directory(compare.result) ? compare.result
                                                                                   : compare.result.parent_path();
  compare.out = out.empty() ? base / "compare" : std::filesystem::path(out);
  return mpath::run_program("mpath-compare", "nothing was written under its final name; run again", flags,
                            [&](const mpath::Options& options) { mpath::run_compare(options, compare); });
}
