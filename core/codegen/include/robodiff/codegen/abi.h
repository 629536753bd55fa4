/* The C ABI of a library made by robodiff's code generator.
 *
 * Every such library exports one object, `robodiff_library` (ROBODIFF_LIBRARY_SYMBOL),
 * that describes everything in it: the ABI version, the generator's version, and for
 * each function its input blocks, its outputs (shape, dense or sparse with the CSR
 * pattern), the work buffers its entry points need, the batch width, and the entry
 * points themselves. A loader needs nothing else (no side files).
 *
 * Calling convention, shared by the single and the batched entry points:
 *  - in[b] points to input block b, out[j] to output block j (one pointer per block, in
 *    the order of the descriptor). Output block j receives `nnz` doubles: row-major
 *    rows*cols for a dense block, the nonzeros in CSR order for a sparse one.
 *  - Batched: knot k of input block b starts at in[b] + k * inputs[b].size, knot k of
 *    output block j at out[j] + k * outputs[j].nnz (array of structures per block; the
 *    library transposes to SIMD lanes internally, `batch_width` knots at a time).
 *  - work points to at least work_size (single) or batch_work_size (batched) doubles,
 *    owned by the caller, contents irrelevant on entry; NULL is allowed when the size is 0.
 *  - Entry points never allocate, keep no state and touch no globals: they are
 *    thread-safe as long as each thread passes its own work buffer and outputs.
 *  - Outputs must not overlap each other or the inputs.
 *
 * Pure C (C99): included by the generated code and by the C++ loader.
 */
#ifndef ROBODIFF_CODEGEN_ABI_H
#define ROBODIFF_CODEGEN_ABI_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Bumped whenever a struct below or the calling convention changes. */
#define ROBODIFF_ABI_VERSION 1u

/* The name of the one exported object of type robodiff_library_desc. */
#define ROBODIFF_LIBRARY_SYMBOL "robodiff_library"

#define ROBODIFF_OUTPUT_DENSE 0u
#define ROBODIFF_OUTPUT_SPARSE 1u

typedef void (*robodiff_eval_fn)(const double* const* in, double* const* out, double* work);
typedef void (*robodiff_eval_batch_fn)(uint64_t n, const double* const* in, double* const* out,
                                       double* work);

typedef struct robodiff_input_desc {
  const char* name;
  uint32_t size; /* doubles */
} robodiff_input_desc;

typedef struct robodiff_output_desc {
  const char* name;
  uint32_t rows, cols;
  uint32_t kind;           /* ROBODIFF_OUTPUT_DENSE or ROBODIFF_OUTPUT_SPARSE */
  uint32_t nnz;            /* doubles written: rows*cols when dense */
  const uint32_t* row_ptr; /* sparse: rows + 1 entries; NULL when dense */
  const uint32_t* col_idx; /* sparse: nnz entries, increasing within a row; NULL when dense */
} robodiff_output_desc;

typedef struct robodiff_function_desc {
  const char* name;
  uint32_t n_inputs;
  const robodiff_input_desc* inputs;
  uint32_t n_outputs;
  const robodiff_output_desc* outputs;
  uint64_t work_size;       /* doubles needed by eval */
  uint64_t batch_work_size; /* doubles needed by eval_batch */
  uint32_t batch_width;     /* knots evaluated together by eval_batch (1: a plain loop) */
  robodiff_eval_fn eval;
  robodiff_eval_batch_fn eval_batch;
} robodiff_function_desc;

typedef struct robodiff_library_desc {
  uint32_t abi_version;     /* ROBODIFF_ABI_VERSION of the generator; checked first */
  uint32_t descriptor_size; /* sizeof(robodiff_library_desc) as the generator saw it */
  const char* generator_version;
  uint32_t n_functions;
  const robodiff_function_desc* functions;
} robodiff_library_desc;

#ifdef __cplusplus
}
#endif

#endif /* ROBODIFF_CODEGEN_ABI_H */
