#!/usr/bin/env python3
"""Packs voxlight's binaries for a lent GPU machine that has CUDA's driver but none of
voxlight's Debian libraries and no package registry (the `device` tool's machines).

The binaries' full library closure is ~365 MB, over what the tool carries (64 MiB), mostly
OpenImageIO's codec and GIS dependencies that the bake never calls. So: the libraries the
binaries and OpenImageIO link directly are copied as they are; deeper ones are replaced by
ABI-shaped stubs (every symbol and symbol version a copied library imports from them, each
function writing its name and aborting if ever called). A stub whose library runs code at
load (a static initialiser) is found by starting each binary with the bundle, and that
library is copied instead; this repeats until every binary starts.

    tools/gpu-check/bundle.py OUT_DIR BINARY...

writes OUT_DIR/libs.tar.xz (lib/) and OUT_DIR/bins.tar.xz (bin/).
"""
import collections, functools, os, re, shutil, subprocess, sys, tempfile

GLIBC = re.compile(r'^(libc|libm|libdl|libpthread|librt|ld-linux-x86-64)\.so')
STUB_OVER_BYTES = 1_500_000  # direct dependencies of OpenImageIO larger than this start as stubs
KEEP_REAL = re.compile(r'^(libOpenImageIO|libtbb|libstdc\+\+|libgcc_s|libopenvdb|libOpenEXR|libImath|libIex|'
                       r'libtinygltf|libstb|libboost|libblosc|libz\.)')


@functools.lru_cache(maxsize=None)  # each stub reads every consumer's symbols: read each once
def run(*args):
    return subprocess.run(args, capture_output=True, text=True).stdout


def needed(path):
    return re.findall(r'\(NEEDED\).*\[(.*)\]', run('readelf', '-d', path))


@functools.lru_cache(maxsize=None)
def dynsyms(path):
    rows = []
    for line in run('readelf', '--dyn-syms', '-W', path).splitlines():
        f = line.split()
        if len(f) >= 8 and f[0].endswith(':') and f[0][:-1].isdigit():
            rows.append((int(f[2], 0), f[3], f[6], f[7]))  # size, type, section, name@version
    return rows


def closure(binaries):
    where = {}
    for b in binaries:
        for line in run('ldd', b).splitlines():
            m = re.match(r'\s*(\S+) => (\S+)', line)
            if m: where[m.group(1)] = m.group(2)
    depth, todo = {}, [(b, 0) for b in binaries]
    while todo:
        path, d = todo.pop()
        for name in needed(path):
            if GLIBC.match(name) or depth.get(name, 99) <= d + 1: continue
            depth[name] = d + 1
            todo.append((where[name], d + 1))
    return {n: (where[n], d) for n, d in depth.items()}


@functools.lru_cache(maxsize=None)
def imports(consumers):
    return {s[3].split('@')[0] for c in consumers for s in dynsyms(c) if s[2] == 'UND'}


def write_stub(name, real_path, consumers, lib_dir, src_dir):
    imported = imports(tuple(consumers))
    by_version, src = collections.defaultdict(list), ['#include <stdlib.h>', '#include <unistd.h>']
    for i, (size, kind, section, full) in enumerate(dynsyms(real_path)):
        base, _, version = full.partition('@')
        if section == 'UND' or base not in imported or kind not in ('FUNC', 'IFUNC', 'OBJECT', 'TLS'): continue
        if kind == 'OBJECT':
            src.append(f'char s{i}[{max(size, 1)}] __asm__("{base}") = {{0}};')
        elif kind == 'TLS':
            src.append(f'__thread char s{i}[{max(size, 1)}] __asm__("{base}");')
        else:
            message = f'stub called: {base} ({name})\\n'
            src.append(f'void s{i}(void) __asm__("{base}"); void s{i}(void) {{ static const char m[] = "{message}"; '
                       f'write(2, m, sizeof m - 1); abort(); }}')
        by_version[version.lstrip('@')].append(base)
    required = set()
    for c in consumers:
        current = None
        for line in run('readelf', '-V', '-W', c).splitlines():
            m = re.search(r'File: (\S+)', line)
            if m: current = m.group(1)
            m = re.search(r'Name: (\S+)', line)
            if m and current == name: required.add(m.group(1))
    versions = [v for v in by_version if v] + sorted(required - set(by_version))
    c_file = os.path.join(src_dir, name + '.c')
    with open(c_file, 'w') as f: f.write('\n'.join(src) + '\n')
    args = ['gcc', '-shared', '-fPIC', '-o', os.path.join(lib_dir, name), c_file, f'-Wl,-soname,{name}']
    if versions:
        nodes = []
        for j, v in enumerate(versions):
            names = by_version.get(v, []) + (by_version.get('', []) if j == 0 else [])
            body = ('global: ' + ' '.join(n + ';' for n in names)) if names else ''
            nodes.append(f'{v} {{ {body}{" local: *;" if j == 0 else ""} }};')
        with open(c_file + '.map', 'w') as f: f.write('\n'.join(nodes) + '\n')
        args.append(f'-Wl,--version-script={c_file}.map')
    subprocess.run(args, check=True)


def main():
    out, binaries = sys.argv[1], [os.path.abspath(b) for b in sys.argv[2:]]
    libs = closure(binaries)
    real = {n for n, (p, d) in libs.items()
            if d == 1 or (d == 2 and (os.path.getsize(p) <= STUB_OVER_BYTES or KEEP_REAL.match(n)))
            or os.path.getsize(p) < 300_000}
    work = tempfile.mkdtemp()
    lib_dir, src_dir = os.path.join(work, 'lib'), os.path.join(work, 'stubs')
    while True:
        shutil.rmtree(lib_dir, ignore_errors=True); shutil.rmtree(src_dir, ignore_errors=True)
        os.makedirs(lib_dir); os.makedirs(src_dir)
        for n in real: shutil.copy(libs[n][0], os.path.join(lib_dir, n))
        consumers = [libs[n][0] for n in real] + binaries
        for n in sorted(set(libs) - real): write_stub(n, libs[n][0], consumers, lib_dir, src_dir)
        env = dict(os.environ, LD_LIBRARY_PATH=lib_dir)
        called = None
        for b in binaries:
            m = re.search(r'stub called: \S+ \((\S+)\)', subprocess.run([b, '--help'], env=env, capture_output=True,
                                                                       text=True).stderr)
            if m: called = m.group(1); break
        if not called: break
        print(f'{called} runs code at load: copied instead of stubbed')
        real.add(called)
    os.makedirs(os.path.join(work, 'bin'))
    for b in binaries: shutil.copy(b, os.path.join(work, 'bin'))
    os.makedirs(out, exist_ok=True)
    for part in ('lib', 'bin'):
        subprocess.run(f'tar cf - {part} | xz -T0 -6 > {os.path.join(os.path.abspath(out), part + "s.tar.xz")}',
                       shell=True, cwd=work, check=True)
    print(f'{len(real)} libraries copied, {len(libs) - len(real)} stubbed; {out}/libs.tar.xz, {out}/bins.tar.xz')
    shutil.rmtree(work)


if __name__ == '__main__':
    main()
