#include "png.hpp"

#include "pmfrag/io/atomic_file.hpp"
#include "pmfrag/render/png_queue.hpp"

#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkRenderWindow.h>
#include <vtkSmartPointer.h>
#include <vtkImageShrink3D.h>
#include <vtkWindowToImageFilter.h>

#include <png.h>
#include <zlib.h>

#include <stdexcept>
#include <string>

namespace pmfrag::render {

namespace {

// libpng's output callback: the encoded bytes go to a string (no C++ exception may cross libpng's C frames).
void append_bytes(png_structp png, png_bytep data, png_size_t size) {
  try {
    static_cast<std::string*>(png_get_io_ptr(png))->append(reinterpret_cast<const char*>(data), size);
  } catch (...) {
    png_error(png, "out of memory");
  }
}

// libpng directly rather than vtkPNGWriter: the picture is flat colours, so the SUB filter with zlib's RLE
// strategy compresses nearly as well as libpng's adaptive filtering with deflate, at a fraction of the time
// (the writer's adaptive filter choice alone was a fifth of `pmfrag render`'s CPU time).
void write_png(vtkImageData* image, const std::string& png_path, int compression) {
  int dims[3];
  image->GetDimensions(dims);
  const int w = dims[0], h = dims[1], comps = image->GetNumberOfScalarComponents();
  if (image->GetScalarType() != VTK_UNSIGNED_CHAR || (comps != 3 && comps != 4))
    throw std::runtime_error(png_path + ": expected 8-bit RGB pixels");
  const auto* pixels = static_cast<const unsigned char*>(image->GetScalarPointer());
  // Encoded in memory, then written whole or not at all (a full disk leaves the previous frame, and says why).
  std::string encoded;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  // volatile: it is read after a longjmp back into this frame
  volatile bool ok = png && info;
  if (ok && setjmp(png_jmpbuf(png)) == 0) {
    png_set_write_fn(png, &encoded, append_bytes, nullptr);
    png_set_IHDR(png, info, static_cast<png_uint_32>(w), static_cast<png_uint_32>(h), 8,
                 comps == 4 ? PNG_COLOR_TYPE_RGB_ALPHA : PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_set_filter(png, 0, PNG_FILTER_SUB);
    png_set_compression_level(png, compression);
    png_set_compression_strategy(png, compression >= 6 ? Z_DEFAULT_STRATEGY : Z_RLE);
    png_write_info(png, info);
    const std::size_t stride = static_cast<std::size_t>(w) * static_cast<std::size_t>(comps);
    for (int y = h - 1; y >= 0; --y)  // VTK's first row is the bottom one
      png_write_row(png, const_cast<png_bytep>(pixels + static_cast<std::size_t>(y) * stride));
    png_write_end(png, nullptr);
  } else {
    ok = false;
  }
  png_destroy_write_struct(png ? &png : nullptr, info ? &info : nullptr);
  if (!ok) throw std::runtime_error(png_path + ": cannot encode the PNG");
  write_file_atomically(png_path, encoded);
}

}  // namespace

struct PngQueue::Job {
  vtkSmartPointer<vtkImageData> image;
  std::string path;
  int compression = 1;
};

PngQueue::PngQueue(std::size_t depth) : depth_(depth < 1 ? 1 : depth), worker_([this] { work(); }) {}

PngQueue::~PngQueue() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    closing_ = true;
  }
  changed_.notify_all();
  worker_.join();
}

void PngQueue::push(std::unique_ptr<Job> job) {
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [this] { return jobs_.size() < depth_ || !error_.empty(); });
  if (!error_.empty()) throw std::runtime_error(error_);
  jobs_.push_back(std::move(job));
  changed_.notify_all();
}

void PngQueue::finish() {
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [this] { return (jobs_.empty() && !busy_) || !error_.empty(); });
  if (!error_.empty()) throw std::runtime_error(error_);
}

void PngQueue::work() {
  for (;;) {
    std::unique_ptr<Job> job;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      changed_.wait(lock, [this] { return !jobs_.empty() || closing_; });
      if (jobs_.empty()) return;
      job = std::move(jobs_.front());
      jobs_.pop_front();
      busy_ = true;
    }
    std::string failed;
    try {
      write_png(job->image, job->path, job->compression);
    } catch (const std::exception& e) {
      failed = e.what();
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      busy_ = false;
      if (!failed.empty() && error_.empty()) error_ = failed;
    }
    changed_.notify_all();
  }
}

namespace detail {

void write_window_png(vtkRenderWindow* window, const std::string& png_path, int compression, PngQueue* queue,
                      int shrink) {
  vtkNew<vtkWindowToImageFilter> grab;
  grab->SetInput(window);
  grab->SetInputBufferTypeToRGB();
  grab->ReadFrontBufferOff();
  grab->ShouldRerenderOff();
  grab->Update();
  vtkImageData* image = grab->GetOutput();
  vtkNew<vtkImageShrink3D> average;
  if (shrink > 1) {
    average->SetInputConnection(grab->GetOutputPort());
    average->SetShrinkFactors(shrink, shrink, 1);
    average->AveragingOn();
    average->Update();
    image = average->GetOutput();
  }
  if (!queue) {
    write_png(image, png_path, compression);
    return;
  }
  auto job = std::make_unique<PngQueue::Job>();
  job->image = vtkSmartPointer<vtkImageData>::New();
  job->image->DeepCopy(image);  // the filters' buffers are reused by the next frame
  job->path = png_path;
  job->compression = compression;
  queue->push(std::move(job));
}

}  // namespace detail

}  // namespace pmfrag::render
