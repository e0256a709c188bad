/* test_h5_append — reopening a result file to append to it, as a resumed run does: a series is
 * cut back to the rows it held at the checkpoint and grows again from there, the rows before
 * are untouched, a dataset written again is replaced, and a file or series that does not fit
 * (missing, other row size, fewer rows than the checkpoint needs) is refused with a message
 * naming the file and the dataset; a buffered file's rows wait for its flush, which
 * nc_h5_flush_due makes once the interval has passed; a flush takes the disk space it needs
 * past the file's end before it writes, and the file's close gives back what it did not use
 * (test_disk_full has the full disk itself). */
#define _GNU_SOURCE   /* fallocate, to ask whether the file system can reserve space */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "nc_h5.h"

static char path[256];

static int setup(void **state)
{
    (void)state;
    const char *dir = getenv("NC_TMP") ? getenv("NC_TMP") : "/tmp";
    snprintf(path, sizeof path, "%s/test_h5_append_%d.h5", dir, (int)getpid());
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    unlink(path);
    return 0;
}

static void write_rows(nc_h5_series *s, int first, int count)
{
    nc_error err;
    for (int r = first; r < first + count; r++) {
        double row[3] = {r, r + 0.25, r + 0.5};
        assert_int_equal(nc_h5_series_append(s, row, &err), 0);
    }
}

static void read_all(double *out, size_t expected_rows)
{
    hid_t file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    assert_true(file >= 0);
    hid_t d = H5Dopen2(file, "/output/u", H5P_DEFAULT);
    hid_t space = H5Dget_space(d);
    hsize_t dims[2];
    H5Sget_simple_extent_dims(space, dims, NULL);
    assert_int_equal(dims[0], expected_rows);
    assert_int_equal(dims[1], 3);
    assert_true(H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, out) >= 0);
    H5Sclose(space);
    H5Dclose(d);
    H5Fclose(file);
}

static void test_truncate_and_append(void **state)
{
    (void)state;
    nc_error err;
    nc_h5_file f;
    nc_h5_series s;
    hsize_t row_dims[1] = {3};
    double one = 1.0;
    hsize_t dims1[1] = {1};
    assert_int_equal(nc_h5_create(&f, path, &err), 0);
    assert_int_equal(nc_h5_series_create(&f, &s, "/output/u", NC_H5_F64, 2, row_dims, &err), 0);
    write_rows(&s, 0, 7);
    assert_int_equal(nc_h5_write(&f, "/summary/max", NC_H5_F64, 1, dims1, &one, &err), 0);
    nc_h5_series_close(&s);
    nc_h5_close(&f);

    /* the checkpoint was taken after 4 rows: rows 4..6 are dropped, then 4..9 written again */
    assert_int_equal(nc_h5_open(&f, path, &err), 0);
    assert_int_equal(nc_h5_series_open(&f, &s, "/output/u", NC_H5_F64, 2, row_dims, 4, &err), 0);
    assert_int_equal(nc_h5_series_rows(&s), 4);
    write_rows(&s, 4, 6);
    double two = 2.0;
    assert_int_equal(nc_h5_write(&f, "/summary/max", NC_H5_F64, 1, dims1, &two, &err), 0);
    nc_h5_series_close(&s);
    nc_h5_close(&f);

    double got[30];
    read_all(got, 10);
    for (int r = 0; r < 10; r++) {
        assert_true(got[3 * r] == r);
        assert_true(got[3 * r + 2] == r + 0.5);
    }
    hid_t file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    hid_t d = H5Dopen2(file, "/summary/max", H5P_DEFAULT);
    double max = 0;
    H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, &max);
    H5Dclose(d);
    H5Fclose(file);
    assert_true(max == 2.0);
}

static void test_refusals(void **state)
{
    (void)state;
    nc_error err;
    nc_h5_file f;
    nc_h5_series s;
    hsize_t row_dims[1] = {3}, other_dims[1] = {4};

    assert_int_not_equal(nc_h5_open(&f, path, &err), 0);           /* no file yet */
    assert_non_null(strstr(err.message, path));

    assert_int_equal(nc_h5_create(&f, path, &err), 0);
    assert_int_equal(nc_h5_series_create(&f, &s, "/output/u", NC_H5_F64, 2, row_dims, &err), 0);
    write_rows(&s, 0, 2);
    nc_h5_series_close(&s);
    nc_h5_close(&f);

    assert_int_equal(nc_h5_open(&f, path, &err), 0);
    assert_int_not_equal(nc_h5_series_open(&f, &s, "/output/v", NC_H5_F64, 2, row_dims, 0, &err), 0);
    assert_non_null(strstr(err.message, "/output/v"));
    nc_h5_series_close(&s);
    assert_int_not_equal(nc_h5_series_open(&f, &s, "/output/u", NC_H5_F64, 2, other_dims, 0, &err), 0);
    assert_non_null(strstr(err.message, "/output/u"));
    nc_h5_series_close(&s);
    assert_int_not_equal(nc_h5_series_open(&f, &s, "/output/u", NC_H5_I32, 2, row_dims, 0, &err), 0);
    nc_h5_series_close(&s);
    assert_int_not_equal(nc_h5_series_open(&f, &s, "/output/u", NC_H5_F64, 2, row_dims, 5, &err), 0);
    assert_non_null(strstr(err.message, "2 rows"));
    nc_h5_series_close(&s);
    nc_h5_close(&f);

    FILE *text = fopen(path, "w");
    assert_non_null(text);
    fputs("not hdf5\n", text);
    fclose(text);
    assert_int_not_equal(nc_h5_open(&f, path, &err), 0);
    assert_non_null(strstr(err.message, "not an HDF5 file"));
}

/* A buffered file: appended rows wait in memory; a flush writes them, and a process that
 * dies after appending more leaves the file readable as that flush wrote it. After a clean
 * close every row is there, in order, for a rank-1 int and a rank-2 double series. */
static void test_buffered_rows_wait_for_flush(void **state)
{
    (void)state;
    hsize_t row_dims[1] = {3};
    for (int die = 1; die >= 0; die--) {
        pid_t pid = fork();
        if (pid == 0) {
            nc_error err;
            nc_h5_file f;
            nc_h5_series s, n;
            if (nc_h5_create(&f, path, &err)) _exit(2);
            nc_h5_set_buffered(&f);
            if (nc_h5_series_create(&f, &s, "/output/u", NC_H5_F64, 2, row_dims, &err) ||
                nc_h5_series_create(&f, &n, "/output/n", NC_H5_I32, 1, NULL, &err))
                _exit(3);
            for (int32_t r = 0; r < 200; r++) {
                double row[3] = {r, r + 0.25, r + 0.5};
                if (nc_h5_series_append(&s, row, &err) || nc_h5_series_append(&n, &r, &err)) _exit(4);
                if (nc_h5_series_rows(&s) != (hsize_t)r + 1) _exit(5);
                if (r == 149 && nc_h5_flush(&f, &err)) _exit(6);
            }
            /* the 50 rows appended since the flush are not in the file yet */
            hid_t space = H5Dget_space(s.dataset);
            hsize_t dims[2] = {0, 0};
            H5Sget_simple_extent_dims(space, dims, NULL);
            H5Sclose(space);
            if (dims[0] != 150) _exit(7);
            if (die) _exit(0);   /* ... and never will be */
            nc_h5_series_close(&s);
            nc_h5_series_close(&n);
            nc_h5_close(&f);
            _exit(0);
        }
        int status = 0;
        waitpid(pid, &status, 0);
        assert_true(WIFEXITED(status));
        assert_int_equal(WEXITSTATUS(status), 0);
        const size_t rows = die ? 150 : 200;
        double got[600];
        read_all(got, rows);
        for (size_t r = 0; r < rows; r++) {
            assert_true(got[3 * r] == (double)r);
            assert_true(got[3 * r + 2] == (double)r + 0.5);
        }
        hid_t file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
        hid_t d = H5Dopen2(file, "/output/n", H5P_DEFAULT);
        int32_t ints[200];
        hid_t space = H5Dget_space(d);
        hsize_t dims[1];
        H5Sget_simple_extent_dims(space, dims, NULL);
        assert_int_equal(dims[0], rows);
        assert_true(H5Dread(d, H5T_NATIVE_INT32, H5S_ALL, H5S_ALL, H5P_DEFAULT, ints) >= 0);
        for (size_t r = 0; r < rows; r++) assert_int_equal(ints[r], (int32_t)r);
        H5Sclose(space);
        H5Dclose(d);
        H5Fclose(file);
    }
}

/* nc_h5_flush_due: not due right after the file became buffered or was flushed; due once
 * NC_H5_FLUSH_INTERVAL_S of wall time passed, and then it writes the rows. */
static void test_flush_due_after_the_interval(void **state)
{
    (void)state;
    nc_error err;
    nc_h5_file f;
    nc_h5_series s;
    assert_int_equal(nc_h5_create(&f, path, &err), 0);
    nc_h5_set_buffered(&f);
    assert_int_equal(nc_h5_series_create(&f, &s, "/t", NC_H5_F64, 1, NULL, &err), 0);
    double x = 1.0;
    hsize_t dims[1] = {0};
    assert_int_equal(nc_h5_series_append(&s, &x, &err), 0);
    assert_int_equal(nc_h5_flush_due(&f, &err), 0);
    hid_t space = H5Dget_space(s.dataset);
    H5Sget_simple_extent_dims(space, dims, NULL);
    H5Sclose(space);
    assert_int_equal(dims[0], 0);   /* not due: the row waits */
    usleep((useconds_t)(NC_H5_FLUSH_INTERVAL_S * 1.2e6));
    assert_int_equal(nc_h5_flush_due(&f, &err), 1);
    space = H5Dget_space(s.dataset);
    H5Sget_simple_extent_dims(space, dims, NULL);
    H5Sclose(space);
    assert_int_equal(dims[0], 1);   /* due: written */
    assert_int_equal(nc_h5_series_append(&s, &x, &err), 0);
    assert_int_equal(nc_h5_flush_due(&f, &err), 0);   /* the interval counts from that write */
    nc_h5_series_close(&s);
    nc_h5_close(&f);
}

static long long bytes_on_disk(const char *file, long long *size, long long *block)
{
    struct stat st;
    assert_int_equal(stat(file, &st), 0);
    *size = (long long)st.st_size;
    *block = (long long)st.st_blksize;
    return (long long)st.st_blocks * 512;
}

static void test_disk_space_taken_then_given_back(void **state)
{
    (void)state;
    /* does this file system reserve space past a file's end? (ext4, xfs, tmpfs do) */
    char probe[300];
    snprintf(probe, sizeof probe, "%s.probe", path);
    int fd = open(probe, O_CREAT | O_WRONLY | O_TRUNC, 0600);
    assert_true(fd >= 0);
    int can_reserve = fallocate(fd, FALLOC_FL_KEEP_SIZE, 0, 1 << 20) == 0;
    close(fd);
    unlink(probe);
    if (!can_reserve) {
        print_message("skipped: the file system of %s cannot reserve space past a file's end\n", path);
        skip();
    }

    nc_error err;
    nc_h5_file f;
    nc_h5_series s;
    assert_int_equal(nc_h5_create(&f, path, &err), 0);
    nc_h5_set_buffered(&f);
    hsize_t row_dims[1] = {1000};   /* 8 kB rows, 4 rows per chunk */
    assert_int_equal(nc_h5_series_create(&f, &s, "/field", NC_H5_F64, 2, row_dims, &err), 0);
    static double row[1000];
    for (int r = 0; r < 50; r++) {
        row[0] = r;
        assert_int_equal(nc_h5_series_append(&s, row, &err), 0);
    }
    assert_int_equal(nc_h5_flush(&f, &err), 0);
    long long size, block, on_disk = bytes_on_disk(path, &size, &block);
    assert_true(size >= 50 * 8000);
    assert_true(on_disk >= size + 32 * 1024);   /* the margin, taken before */
    nc_h5_series_close(&s);
    nc_h5_close(&f);
    on_disk = bytes_on_disk(path, &size, &block);
    assert_true(on_disk < size + 2 * block + 8 * 1024);   /* given back: the last blocks are left */
    double first[1000];
    hid_t file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    hid_t d = H5Dopen2(file, "/field", H5P_DEFAULT);
    hid_t space = H5Dget_space(d);
    hsize_t dims[2];
    H5Sget_simple_extent_dims(space, dims, NULL);
    assert_int_equal(dims[0], 50);
    hsize_t start[2] = {49, 0}, count[2] = {1, 1000};
    H5Sselect_hyperslab(space, H5S_SELECT_SET, start, NULL, count, NULL);
    hid_t mem = H5Screate_simple(1, count + 1, NULL);
    assert_true(H5Dread(d, H5T_NATIVE_DOUBLE, mem, space, H5P_DEFAULT, first) >= 0);
    assert_true(first[0] == 49.0);
    H5Sclose(mem);
    H5Sclose(space);
    H5Dclose(d);
    H5Fclose(file);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_truncate_and_append, setup, teardown),
        cmocka_unit_test_setup_teardown(test_refusals, setup, teardown),
        cmocka_unit_test_setup_teardown(test_buffered_rows_wait_for_flush, setup, teardown),
        cmocka_unit_test_setup_teardown(test_flush_due_after_the_interval, setup, teardown),
        cmocka_unit_test_setup_teardown(test_disk_space_taken_then_given_back, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
