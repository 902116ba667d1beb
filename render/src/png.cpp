#include "png.hpp"

#include <vtkNew.h>
#include <vtkPNGWriter.h>
#include <vtkRenderWindow.h>
#include <vtkWindowToImageFilter.h>

#include <filesystem>
#include <stdexcept>

namespace pmfrag::render::detail {

void write_window_png(vtkRenderWindow* window, const std::string& png_path, int compression) {
  vtkNew<vtkWindowToImageFilter> grab;
  grab->SetInput(window);
  grab->SetInputBufferTypeToRGB();
  grab->ReadFrontBufferOff();
  grab->ShouldRerenderOff();
  grab->Update();
  const std::string tmp = png_path + ".tmp.png";
  vtkNew<vtkPNGWriter> png;
  png->SetCompressionLevel(compression);
  png->SetFileName(tmp.c_str());
  png->SetInputConnection(grab->GetOutputPort());
  png->Write();
  if (png->GetErrorCode() != 0) throw std::runtime_error(png_path + ": PNG writer failed");
  std::filesystem::rename(tmp, png_path);
}

}  // namespace pmfrag::render::detail
