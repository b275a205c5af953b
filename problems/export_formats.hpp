#pragma once
// The writers of `liedyn export` (problems/export.hpp, where the formats are described), one
// per format, each adding its files to an output folder's unit; internal to problems/.

#include <cstddef>
#include <string>
#include <vector>

#include "export.hpp"
#include "export_geometry.hpp"
#include "output_folder.hpp"
#include "recorded_run.hpp"

namespace liedyn {

struct ExportJob {
  const RecordedRun& run;
  const ExportGeometry& geometry;
  std::vector<std::size_t> frames;  // the exported frames: indices of the run's written frames
  const ExportOptions& options;
};

// Each returns the names of the files it added to the folder's unit.
std::vector<std::string> write_gltf(const ExportJob& job, OutputFolder& folder);  // export_gltf.cpp
std::vector<std::string> write_obj(const ExportJob& job, OutputFolder& folder);   // export.cpp
std::vector<std::string> write_vtk(const ExportJob& job, OutputFolder& folder);   // export_vtk.cpp

// Shared by the text formats.
// "frame_NNNNNN.<extension>", N the run's frame number (6 digits at least).
std::string frame_file_name(int frame_number, const char* extension);
// x in the shortest text that reads back as the same float, or double (std::to_chars).
void append_float(std::string& out, float x);
std::string shortest(double x);
// Text from the run (a title, an object name) made safe for a one-line comment: control
// characters become spaces.
std::string one_line(const std::string& text);

}  // namespace liedyn
