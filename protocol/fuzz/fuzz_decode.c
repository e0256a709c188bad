/* libFuzzer target for the protocol decoder (`make fuzz`, corpus replay in CI).
 *
 * Input layout, so the fuzzer can shape both the header and the frames:
 *   byte 0            number of data frames n (taken modulo 20, so "too many" is reachable)
 *   bytes 1 .. 2n     little-endian u16 length of each frame
 *   then              the frames' bytes, one after another (cut short if the input ends)
 *   the rest          the JSON header
 * Any input must be either decoded or rejected with a message; ASan/UBSan catch the rest.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "proto.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static proto_message message; /* keeps its buffers between runs, as a real endpoint does */
    if (size < 1) return 0;
    size_t n = data[0] % 20;
    size_t offset = 1;
    size_t lengths[20];
    const void *frames[20];
    for (size_t i = 0; i < n; i++) {
        lengths[i] = offset + 2 <= size ? (size_t)data[offset] | (size_t)data[offset + 1] << 8 : 0;
        offset += 2;
    }
    if (offset > size) offset = size;
    for (size_t i = 0; i < n; i++) {
        if (lengths[i] > size - offset) lengths[i] = size - offset;
        frames[i] = data + offset;
        offset += lengths[i];
    }
    nc_error err;
    if (proto_decode(&message, data + offset, size - offset, frames, lengths, n, 1u << 20,
                     &err) == 0) {
        /* a decoded message must re-encode to a header that decodes to the same message;
         * reading its arrays must stay in bounds */
        static proto_message again;
        char *header;
        size_t length;
        if (proto_encode_header(&message, &header, &length, &err) != 0) __builtin_trap();
        if (proto_decode(&again, header, length, frames, lengths, n, 1u << 20, &err) != 0)
            __builtin_trap();
        free(header);
        if (again.type != message.type || again.step != message.step ||
            again.iteration != message.iteration || again.time_s != message.time_s ||
            again.dt_s != message.dt_s || again.n_arrays != message.n_arrays ||
            again.n_values != message.n_values || strcmp(again.text, message.text) != 0 ||
            strcmp(again.role, message.role) != 0 || strcmp(again.name, message.name) != 0)
            __builtin_trap();
        double sum = 0;
        for (size_t i = 0; i < message.n_arrays; i++) {
            const proto_array *a = &message.arrays[i];
            if (a->dtype == PROTO_F64)
                for (size_t k = 0; k < a->count; k++) sum += ((const double *)a->data)[k];
            else
                for (size_t k = 0; k < a->count; k++) sum += ((const int32_t *)a->data)[k];
        }
        if (sum != sum) __builtin_trap(); /* NaN must have been rejected */
    } else if (err.message[0] == '\0') {
        __builtin_trap(); /* every rejection says why */
    }
    return 0;
}
