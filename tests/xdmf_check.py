"""xdmf_check — checks that an XDMF file written by fem_solver or dem_solver describes its HDF5
data exactly, the way a reader such as ParaView will take it (used by the script tests; needs
only Debian's python3 with h5py and numpy).

    from xdmf_check import check_xdmf, grid_counts, self_test
    problems = check_xdmf("out/fem.xdmf", "/output/time")   # [] when the file is right
    grid_counts("out/particles.xdmf")                        # {"particles": 101}
    self_test("out", "fem.xdmf", "/output/time", scratch)    # [] when every corruption is caught

    /usr/bin/python3 tests/xdmf_check.py FILE.xdmf TIMES_DATASET   (exit 1 and the problems)
    /usr/bin/python3 tests/xdmf_check.py --self-test DIR FILE.xdmf TIMES_DATASET SCRATCH_DIR

check_xdmf(path, times) reports, per DataItem and grid:
- every HDF reference `file.h5:/path` names a file next to the XDMF file (relative, present),
  and a dataset there with exactly the declared Dimensions, NumberType and Precision (XDMF's
  defaults: Float, 4 bytes); an XML DataItem holds as many numbers as its Dimensions say;
- a HyperSlab's start/stride/count stay inside its source and select the declared Dimensions;
  so does an XDMF 3 selection `file.h5:/path|start:stride:count:space` (what both programs
  write: ParaView's default reader, Xdmf3, reads it), whose space must match the dataset
  except along dimension 0, where a series grows;
- topology and geometry agree: connectivity is (cells x nodes per cell) with indices of existing
  points, a Polyvertex has one cell per point, XYZ geometry is (points x 3);
- an Attribute has one value (Scalar) or 3 (Vector) per point (Center="Node") or per cell
  (Center="Cell"), and names are unique within a grid;
- in each temporal collection the Time values increase strictly and equal the times of the HDF5
  output (dataset `times`, e.g. /output/time of fem.h5, /time of dem.h5) at the row the grid's
  data come from: row k of a time series (a selection or HyperSlab starting at k). Both programs print times with 17 digits, which round-trips a double, so
  the comparison is exact.
"""
import os
import re
import shutil
import sys
import xml.etree.ElementTree as ET

import h5py
import numpy as np

NODES_PER_CELL = {"Polyvertex": 1, "Triangle": 3, "Quadrilateral": 4, "Tetrahedron": 4,
                  "Hexahedron": 8}
COMPONENTS = {"Scalar": 1, "Vector": 3, "Tensor6": 6, "Tensor": 9}
# NumberType -> numpy dtype kind; Char/UChar are 1-byte integers
KINDS = {"Float": "f", "Int": "i", "UInt": "u", "Char": "i", "UChar": "u"}
STEP_GROUP = re.compile(r"^/steps/(\d+)/")


def _dims(text):
    return tuple(int(d) for d in text.split())


def _squeeze(dims):
    """Dimensions without axes of length 1 (a HyperSlab of count 1 x 4 x 3 is declared 4 x 3)."""
    return tuple(d for d in dims if d != 1)


class _Checker:
    def __init__(self, path, times_path):
        self.path = path
        self.dir = os.path.dirname(os.path.abspath(path))
        self.times_path = times_path
        self.problems = []
        self.files = {}
        self.times = None

    def problem(self, where, text):
        self.problems.append("%s: %s: %s" % (os.path.basename(self.path), where, text))

    def h5(self, name, where):
        """The open HDF5 file `name` (relative to the XDMF file), or None (problem recorded)."""
        if name in self.files:
            return self.files[name]
        f = None
        if os.path.isabs(name) or os.path.dirname(name):
            self.problem(where, "HDF5 file %s is not a plain name next to the XDMF file" % name)
        elif not os.path.isfile(os.path.join(self.dir, name)):
            self.problem(where, "missing file %s" % name)
        else:
            try:
                f = h5py.File(os.path.join(self.dir, name), "r")
            except OSError as e:
                self.problem(where, "cannot open %s: %s" % (name, e))
        self.files[name] = f
        return f

    def close(self):
        for f in self.files.values():
            if f is not None:
                f.close()

    # ---- data items ---------------------------------------------------------------------
    def item(self, item, where):
        """Checks one DataItem; returns (declared dims, values or None, source row or None)."""
        if item is None or item.get("Dimensions") is None:
            self.problem(where, "DataItem without Dimensions")
            return None, None, None
        try:
            dims = _dims(item.get("Dimensions"))
        except ValueError:
            self.problem(where, "Dimensions %r are not integers" % item.get("Dimensions"))
            return None, None, None
        if item.get("ItemType") == "HyperSlab":
            return self.hyperslab(item, dims, where)
        fmt = item.get("Format", "XML")
        if fmt == "XML":
            try:
                values = np.array([float(v) for v in (item.text or "").split()])
            except ValueError:
                self.problem(where, "XML DataItem holds non-numbers")
                return dims, None, None
            if values.size != int(np.prod(dims)):
                self.problem(where, "XML DataItem holds %d numbers, Dimensions %s need %d"
                             % (values.size, dims, int(np.prod(dims))))
                return dims, None, None
            return dims, values.reshape(dims), None
        if fmt != "HDF":
            self.problem(where, "unsupported Format %s" % fmt)
            return dims, None, None
        ref = (item.text or "").strip()
        if ":" not in ref:
            self.problem(where, "HDF reference %r is not file.h5:/path" % ref)
            return dims, None, None
        name, dset = ref.split(":", 1)
        selection = None
        if "|" in dset:
            dset, selection = dset.split("|", 1)
        f = self.h5(name, where)
        if f is None:
            return dims, None, None
        if dset not in f or not isinstance(f[dset], h5py.Dataset):
            self.problem(where, "missing dataset %s in %s" % (dset, name))
            return dims, None, None
        d = f[dset]
        number_type = item.get("NumberType", item.get("DataType", "Float"))
        precision = int(item.get("Precision", "1" if number_type in ("Char", "UChar") else "4"))
        if (KINDS.get(number_type) != d.dtype.kind or d.dtype.itemsize != precision):
            self.problem(where, "%s:%s is %s, the XDMF file declares %s of %d bytes"
                         % (name, dset, d.dtype, number_type, precision))
        if selection is not None:
            return self.selection(name, dset, d, selection, dims, where)
        if d.shape != dims:
            self.problem(where, "%s:%s has dimensions %s, the XDMF file declares %s"
                         % (name, dset, d.shape, dims))
            return dims, None, None
        row = None
        m = STEP_GROUP.match(dset)
        if m:
            row = int(m.group(1))
        return dims, d, row

    def selection(self, name, dset, d, text, dims, where):
        """An XDMF 3 HDF selection FILE:DATASET|start:stride:count:space (one row of a series):
        the space has the dataset's rank and sizes except along dimension 0 (the series grows
        there, the space names the rows it needs), the selection stays inside the dataset and
        selects the declared Dimensions."""
        try:
            start, stride, count, space = (np.array(_dims(p), dtype=int) for p in text.split(":"))
        except ValueError:
            self.problem(where, "selection %r is not start:stride:count:space" % text)
            return dims, None, None
        rank = len(d.shape)
        if not (len(start) == len(stride) == len(count) == len(space) == rank):
            self.problem(where, "selection %r does not have the rank %d of %s:%s" % (text, rank, name, dset))
            return dims, None, None
        if tuple(space[1:]) != d.shape[1:] or space[0] > d.shape[0]:
            self.problem(where, "%s:%s has dimensions %s, the selection's space is %s"
                         % (name, dset, d.shape, tuple(space)))
            return dims, None, None
        last = start + (count - 1) * stride
        if (start < 0).any() or (stride < 1).any() or (count < 1).any() or (last >= space).any():
            self.problem(where, "selection start %s stride %s count %s outside the space %s"
                         % (list(start), list(stride), list(count), tuple(space)))
            return dims, None, None
        if _squeeze(tuple(count)) != _squeeze(dims):
            self.problem(where, "selection of %s, the XDMF file declares %s" % (tuple(count), dims))
            return dims, None, None
        row = None
        if self.times is not None and d.shape[0] == len(self.times) and count[0] == 1:
            row = int(start[0])
        sl = tuple(slice(a, a + (c - 1) * st + 1, st) for a, st, c in zip(start, stride, count))
        return dims, np.asarray(d[sl]).reshape(dims), row

    def hyperslab(self, item, dims, where):
        children = item.findall("DataItem")
        if len(children) != 2:
            self.problem(where, "HyperSlab needs two DataItems (start/stride/count, source)")
            return dims, None, None
        sel_dims, sel, _ = self.item(children[0], where + " (selection)")
        src_dims, src, _ = self.item(children[1], where + " (source)")
        if sel is None or src_dims is None:
            return dims, None, None
        rank = len(src_dims)
        if sel_dims != (3, rank):
            self.problem(where, "HyperSlab selection is %s, expected 3 x %d" % (sel_dims, rank))
            return dims, None, None
        start, stride, count = (sel[i].astype(int) for i in range(3))
        last = start + (count - 1) * stride
        if (start < 0).any() or (stride < 1).any() or (count < 1).any() or \
                (last >= np.array(src_dims)).any():
            self.problem(where, "HyperSlab start %s stride %s count %s outside the source %s"
                         % (list(start), list(stride), list(count), src_dims))
            return dims, None, None
        if _squeeze(tuple(count)) != _squeeze(dims):
            self.problem(where, "HyperSlab selects %s, declared Dimensions %s" % (tuple(count), dims))
            return dims, None, None
        row = None
        if self.times is not None and src_dims[0] == len(self.times) and count[0] == 1:
            row = int(start[0])
        values = None
        if src is not None:
            sl = tuple(slice(a, a + (c - 1) * s + 1, s) for a, s, c in zip(start, stride, count))
            values = np.asarray(src[sl]).reshape(dims)
        return dims, values, row

    # ---- grids ----------------------------------------------------------------------------
    def grid(self, grid, where):
        """Checks one uniform grid; returns the rows its data come from."""
        rows = set()

        def use(item, what):
            dims, values, row = self.item(item, what)
            if row is not None:
                rows.add(row)
            return dims, values

        geometry = grid.find("Geometry")
        n_points = None
        if geometry is None:
            self.problem(where, "no Geometry")
        else:
            gtype = geometry.get("GeometryType", "XYZ")
            width = {"XYZ": 3, "XY": 2}.get(gtype)
            dims, _ = use(geometry.find("DataItem"), where + " Geometry")
            if width is None:
                self.problem(where, "unsupported GeometryType %s" % gtype)
            elif dims is not None:
                if len(dims) != 2 or dims[1] != width:
                    self.problem(where, "%s geometry has Dimensions %s, expected (points x %d)"
                                 % (gtype, dims, width))
                else:
                    n_points = dims[0]
        topology = grid.find("Topology")
        n_cells = None
        if topology is None:
            self.problem(where, "no Topology")
        else:
            ttype = topology.get("TopologyType")
            npe = NODES_PER_CELL.get(ttype)
            if ttype == "Polyline":
                npe = int(topology.get("NodesPerElement", "0"))
            if not npe:
                self.problem(where, "unsupported TopologyType %s" % ttype)
            n_cells = int(topology.get("NumberOfElements", "-1"))
            item = topology.find("DataItem")
            if item is None:
                if ttype != "Polyvertex":
                    self.problem(where, "%s topology without connectivity" % ttype)
                elif n_points is not None and n_cells != n_points:
                    self.problem(where, "Polyvertex of %d cells for %d points" % (n_cells, n_points))
            else:
                dims, conn = use(item, where + " Topology")
                if dims is not None and npe == 1 and dims == (n_cells,):
                    pass   # one node per cell: a plain list of point indices
                elif dims is not None and npe and dims != (n_cells, npe):
                    self.problem(where, "connectivity %s, expected %d cells x %d nodes per cell"
                                 % (dims, n_cells, npe))
                elif conn is not None and n_points is not None and conn.size:
                    conn = np.asarray(conn)
                    if conn.min() < 0 or conn.max() >= n_points:
                        self.problem(where, "connectivity indices %d..%d outside 0..%d"
                                     % (conn.min(), conn.max(), n_points - 1))
        names = set()
        for attribute in grid.findall("Attribute"):
            name = attribute.get("Name")
            what = "%s Attribute %s" % (where, name)
            if name in names:
                self.problem(what, "duplicate attribute name")
            names.add(name)
            center = attribute.get("Center", "Node")
            atype = attribute.get("AttributeType", "Scalar")
            dims, _ = use(attribute.find("DataItem"), what)
            n = {"Node": n_points, "Cell": n_cells}.get(center, -1)
            width = COMPONENTS.get(atype)
            if n == -1 or width is None:
                self.problem(what, "unsupported Center %s or AttributeType %s" % (center, atype))
            elif dims is not None and n is not None:
                expected = (n,) if width == 1 else (n, width)
                if dims != expected and not (width == 1 and dims == (n, 1)):
                    self.problem(what, "Center=%s %s has Dimensions %s, expected %s"
                                 % (center, atype, dims, expected))
        return rows

    def collection(self, coll, where):
        grids = coll.findall("Grid")
        previous = None
        for k, grid in enumerate(grids):
            gwhere = "%s grid %s" % (where, grid.get("Name", k))
            rows = self.grid(grid, gwhere)
            time = grid.find("Time")
            if time is None or time.get("Value") is None:
                self.problem(gwhere, "no Time Value in a temporal collection")
                continue
            t = float(time.get("Value"))
            if previous is not None and not t > previous:
                self.problem(gwhere, "Time %.17g does not increase (previous %.17g)" % (t, previous))
            previous = t
            if self.times is None:
                continue
            if len(rows) > 1:
                self.problem(gwhere, "data from different output rows %s" % sorted(rows))
                continue
            row = rows.pop() if rows else k
            if row >= len(self.times):
                self.problem(gwhere, "row %d beyond the %d output times" % (row, len(self.times)))
            elif t != self.times[row]:
                self.problem(gwhere, "Time %.17g, the HDF5 output has %.17g at row %d"
                             % (t, self.times[row], row))

    def run(self):
        try:
            root = ET.parse(self.path).getroot()
        except (ET.ParseError, OSError) as e:
            self.problem("file", "not readable XML: %s" % e)
            return
        if root.tag != "Xdmf" or root.find("Domain") is None:
            self.problem("file", "root is <%s>, expected <Xdmf><Domain>" % root.tag)
            return
        # the time series: in the (single) HDF5 file the top-level grids refer to
        refs = [i.text.strip().split(":", 1)[0] for i in root.iter("DataItem")
                if i.get("Format") == "HDF" and i.text and ":" in i.text]
        if self.times_path and refs:
            f = self.h5(refs[0], "times")
            if f is not None:
                if self.times_path in f:
                    self.times = f[self.times_path][:]
                else:
                    self.problem("times", "missing dataset %s in %s" % (self.times_path, refs[0]))
        for coll in root.find("Domain").findall("Grid"):
            where = "collection %s" % coll.get("Name")
            if coll.get("GridType") == "Collection":
                if coll.get("CollectionType") != "Temporal":
                    self.problem(where, "collection is not Temporal")
                self.collection(coll, where)
            else:
                self.grid(coll, where)


def check_xdmf(path, times=None):
    """Problems found in the XDMF file `path` (list of strings, empty when it is right); `times`
    names the dataset of output times in its HDF5 file (e.g. "/output/time")."""
    checker = _Checker(path, times)
    try:
        checker.run()
    finally:
        checker.close()
    return checker.problems


def grid_counts(path):
    """Number of grids of each temporal collection: {collection name: count}."""
    root = ET.parse(path).getroot()
    return {c.get("Name"): len(c.findall("Grid")) for c in root.find("Domain").findall("Grid")
            if c.get("GridType") == "Collection"}


def self_test(out_dir, xdmf_name, times, scratch):
    """Corrupts copies of a correct result folder and returns the corruptions check_xdmf did not
    catch (empty list: all caught). `scratch` is a folder for the copies."""
    missed = []
    path = os.path.join(out_dir, xdmf_name)
    if check_xdmf(path, times):
        return ["the uncorrupted file already fails: %s" % check_xdmf(path, times)[:3]]

    def corrupt(label, edit_xml=None, edit_h5=None, expect=""):
        copy = os.path.join(scratch, "xdmf_self_test_" + label)
        shutil.rmtree(copy, ignore_errors=True)
        shutil.copytree(out_dir, copy)
        cpath = os.path.join(copy, xdmf_name)
        if edit_xml:
            tree = ET.parse(cpath)
            if edit_xml(tree.getroot()) is False:   # not detectable in this file
                shutil.rmtree(copy, ignore_errors=True)
                return
            tree.write(cpath)
        if edit_h5:
            edit_h5(copy)
        problems = check_xdmf(cpath, times)
        if not any(expect in p for p in problems):
            missed.append("%s not caught (problems: %s)" % (label, problems[:3]))
        shutil.rmtree(copy, ignore_errors=True)

    def hdf_items(root):
        return [i for i in root.iter("DataItem") if i.get("Format") == "HDF"]

    def grids(root):
        return [g for c in root.find("Domain").findall("Grid") for g in c.findall("Grid")]

    def h5_name(root):
        return hdf_items(root)[0].text.strip().split(":")[0]

    def wrong_dims(root):
        item = hdf_items(root)[-1]
        dims = _dims(item.get("Dimensions"))
        item.set("Dimensions", " ".join(str(d + (1 if i == 0 else 0)) for i, d in enumerate(dims)))

    def wrong_precision(root):
        for item in hdf_items(root):
            if item.get("Precision") == "8":
                item.set("Precision", "4")
                return

    def missing_file(root):
        item = hdf_items(root)[-1]
        item.text = "absent.h5:" + item.text.strip().split(":", 1)[1]

    def same_time(root):
        g = grids(root)
        g[1].find("Time").set("Value", g[0].find("Time").get("Value"))

    def shifted_time(root):
        t = grids(root)[-1].find("Time")
        t.set("Value", repr(float(t.get("Value")) * (1 + 1e-9) + 1e-9))

    def one_more_cell(root):
        topology = grids(root)[0].find("Topology")
        topology.set("NumberOfElements", str(int(topology.get("NumberOfElements")) + 1))

    def point_attribute_on_cells(root):
        """A point attribute declared on cells (only detectable with fewer cells than points:
        a Polyvertex has as many cells as points)."""
        for g in grids(root):
            if g.find("Topology").get("TopologyType") == "Polyvertex":
                continue
            for a in g.findall("Attribute"):
                if a.get("Center") == "Node":
                    a.set("Center", "Cell")
                    return True
        return False

    def missing_dataset(copy):
        root = ET.parse(os.path.join(copy, xdmf_name)).getroot()
        name, dset = hdf_items(root)[-1].text.strip().split(":", 1)
        with h5py.File(os.path.join(copy, name), "a") as f:
            del f[dset.split("|")[0]]

    def longer_dataset(copy):
        root = ET.parse(os.path.join(copy, xdmf_name)).getroot()
        geometry = grids(root)[0].find("Geometry").find("DataItem")
        if geometry.get("ItemType") == "HyperSlab":
            geometry = geometry.findall("DataItem")[1]
        name, dset = geometry.text.strip().split(":", 1)
        dset = dset.split("|")[0]
        with h5py.File(os.path.join(copy, h5_name(root)), "a") as f:
            data = f[dset][:]
            del f[dset]
            # a series may grow along dimension 0; one more coordinate per point may not
            f[dset] = np.concatenate([data, data[..., -1:]], axis=-1) if data.ndim else data

    corrupt("wrong_dimensions", edit_xml=wrong_dims, expect="declares")
    corrupt("wrong_precision", edit_xml=wrong_precision, expect="bytes")
    corrupt("missing_file", edit_xml=missing_file, expect="missing file")
    corrupt("time_not_increasing", edit_xml=same_time, expect="does not increase")
    corrupt("time_not_in_output", edit_xml=shifted_time, expect="the HDF5 output has")
    corrupt("one_more_cell", edit_xml=one_more_cell, expect="cells")
    corrupt("node_attribute_declared_on_cells", edit_xml=point_attribute_on_cells, expect="Center=Cell")
    corrupt("missing_dataset", edit_h5=missing_dataset, expect="missing dataset")
    corrupt("dataset_longer_than_declared", edit_h5=longer_dataset, expect="dimensions")
    return missed


def main():
    if len(sys.argv) == 6 and sys.argv[1] == "--self-test":
        problems = self_test(*sys.argv[2:])
    elif len(sys.argv) in (2, 3):
        problems = check_xdmf(sys.argv[1], sys.argv[2] if len(sys.argv) == 3 else None)
    else:
        sys.exit(__doc__)
    for p in problems:
        print(p)
    sys.exit(1 if problems else 0)


if __name__ == "__main__":
    main()
