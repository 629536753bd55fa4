#pragma once
// The parts of the _robodiff module, each registered by its own file.
#include <nanobind/nanobind.h>

namespace robodiff::python {

void bindClient(nanobind::module_& m);    // client_binding.cpp: Client, ModelInfo
void bindFunction(nanobind::module_& m);  // function_binding.cpp: Function
void bindReference(nanobind::module_& m); // reference_binding.cpp: ReferenceModel (robodiff.reference)
void bindCheck(nanobind::module_& m);     // check_binding.cpp: check_spec (robodiff.check)
void bindWarmup(nanobind::module_& m);    // warmup_binding.cpp: warmup
void bindCache(nanobind::module_& m);     // cache_binding.cpp: cache_entries, default_cache_dir
void bindJobs(nanobind::module_& m);      // jobs_binding.cpp: JobInfo, submit_job, job_status, ...
void bindTiming(nanobind::module_& m);    // timing_binding.cpp: _native_seconds_per_call (bench/python)

}  // namespace robodiff::python
