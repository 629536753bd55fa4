// A function for the service benchmarks: the robot loaded and the spec built on a running
// robodiffd, returned once its compiled library (not the interpreter) serves it.
#pragma once

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>

#include "bench_daemon.hpp"
#include "robodiff/client/connection.hpp"

namespace bench {

inline void check(const robodiff::Status& s, const char* what) {
  if (s.ok()) return;
  std::fprintf(stderr, "bench: %s failed: %s: %s\n", what, robodiff::toString(s.code).c_str(), s.message.c_str());
  std::exit(1);
}

inline robodiff::rpc::GetFunctionReply compiledFunction(robodiff::client::Connection& c,
                                                        const std::filesystem::path& urdf,
                                                        const std::filesystem::path& spec) {
  robodiff::rpc::LoadModelRequest load;
  load.urdf = readText(urdf);
  robodiff::rpc::LoadModelReply model;
  check(c.loadModel(load, model), "LoadModel");
  robodiff::rpc::GetFunctionRequest get;
  get.model_id = model.model_id;
  get.spec_json = readText(spec);
  get.wait = true;
  robodiff::rpc::GetFunctionReply function;
  check(c.getFunction(get, function), "GetFunction");
  for (int i = 0; i <= 1200; ++i) {
    std::vector<robodiff::rpc::FunctionSummary> functions;
    check(robodiff::client::listAllFunctions(c, {}, functions), "ListFunctions");
    for (const robodiff::rpc::FunctionSummary& f : functions)
      if (f.function_id == function.function_id && f.compiled) return function;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  std::fprintf(stderr, "bench: %s was not compiled within 120 s\n", spec.c_str());
  std::exit(1);
}

}  // namespace bench
