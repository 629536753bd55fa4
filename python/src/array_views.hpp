#pragma once
// A Python object's buffer (a numpy array) viewed as C-contiguous float64, or refused
// with a message naming what was given and what is needed: never a silent copy.
#include <Python.h>

#include <cstddef>
#include <string>

#include <nanobind/nanobind.h>

namespace robodiff::python {

class DoubleArrayView {
 public:
  DoubleArrayView() = default;
  // Throws nanobind::type_error (not an array, not float64) or nanobind::value_error
  // (not C-contiguous, read-only when `writable`). Messages name the argument: "input
  // 'q'" for an input, "out['jacobian']" for a `writable` output.
  DoubleArrayView(nanobind::handle object, const std::string& name, bool writable);
  DoubleArrayView(DoubleArrayView&& other) noexcept;
  DoubleArrayView& operator=(DoubleArrayView&& other) noexcept;
  DoubleArrayView(const DoubleArrayView&) = delete;
  DoubleArrayView& operator=(const DoubleArrayView&) = delete;
  ~DoubleArrayView();

  int ndim() const { return ndim_; }
  std::size_t dim(int i) const { return static_cast<std::size_t>(shape_[i]); }
  double* data() const { return data_; }
  std::size_t size() const { return size_; }
  // "(7,)", "(20, 7)": the shape as numpy prints it.
  std::string shapeText() const;

 private:
  bool viewNumpyArray(nanobind::handle object, bool writable);
  void viewBuffer(nanobind::handle object, const std::string& name, bool writable);

  // What is viewed: a numpy array's own fields (the fast path: the caller keeps the array
  // alive), or the buffer protocol's view of anything else, held until destruction.
  double* data_ = nullptr;
  int ndim_ = 0;
  const Py_ssize_t* shape_ = nullptr;
  std::size_t size_ = 0;
  Py_buffer view_{};
  bool held_ = false;
};

// "input 'q'" or "out['jacobian']": how messages name an argument.
std::string argumentLabel(const std::string& name, bool output);

// str(object), as Python prints it ("?" if even that fails).
std::string textOf(nanobind::handle object);

// numpy's spelling of a shape: (7,) or (20, 7).
std::string shapeText(std::size_t a);
std::string shapeText(std::size_t a, std::size_t b);

}  // namespace robodiff::python
