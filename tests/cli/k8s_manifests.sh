#!/bin/sh
# k8s_manifests.sh - deploy/k8s/*.yaml hang together. No cluster is used (and
# none was: docs/deploy.md says so): each document parses (python3's yaml),
# names a known apiVersion and kind; each Service selects the pods of a
# Deployment or Job in the same file set and targets a port they declare;
# each Deployment's selector matches its pods; the worker and master
# arguments are options their man pages describe, --secret-file lies in the
# mounted Secret portray-secret, the dialling workers dial the master's
# Service at the port it accepts on, and the headless variant's -w names
# its headless Service; the Secret's placeholder is not base64, so the
# file cannot be applied unchanged. Skipped (exit 77) without python3 and
# its yaml module.
if ! command -v python3 >/dev/null 2>&1; then
	echo "python3 not installed"
	exit 77
fi
if ! python3 -c 'import yaml' 2>/dev/null; then
	echo "python3 has no yaml module (PyYAML)"
	exit 77
fi
python3 - deploy/k8s docs/man <<'PY'
import base64, binascii, glob, os, re, sys
import yaml

k8s, mandir = sys.argv[1], sys.argv[2]
errors = []
def err(msg):
    errors.append(msg)

KINDS = {'Secret': 'v1', 'Service': 'v1', 'PersistentVolumeClaim': 'v1',
         'Deployment': 'apps/v1', 'Job': 'batch/v1'}

def man_options(page):
    text = open(os.path.join(mandir, page)).read().replace('\\-', '-')
    return set(re.findall(r'--[a-z][a-z-]*', text))
OPTS = {'portray-master': man_options('portray-master.1'),
        'portray-worker': man_options('portray-worker.1')}

files = {}
for f in sorted(glob.glob(os.path.join(k8s, '*.yaml'))):
    try:
        docs = [d for d in yaml.safe_load_all(open(f)) if d is not None]
    except yaml.YAMLError as e:
        err('%s: %s' % (f, e))
        continue
    for d in docs:
        kind, api = d.get('kind'), d.get('apiVersion')
        if KINDS.get(kind) != api:
            err('%s: kind %s with apiVersion %s' % (f, kind, api))
        if not d.get('metadata', {}).get('name'):
            err('%s: a %s without a name' % (f, kind))
    files[os.path.basename(f)] = docs
    print('parsed %s: %s' % (f, ', '.join('%s/%s' % (d['kind'], d['metadata']['name']) for d in docs)))

need = ['portray-secret.yaml', 'portray-master-job.yaml', 'portray-worker-deployment.yaml', 'portray-headless.yaml']
for n in need:
    if n not in files:
        err('missing %s' % n)
if errors:
    print('\n'.join('FAIL: ' + e for e in errors))
    sys.exit(1)

# the Secret: a placeholder that kubectl would refuse to decode
sec = files['portray-secret.yaml'][0]
val = sec.get('data', {}).get('secret', '')
try:
    base64.b64decode(val, validate=True)
    err('portray-secret.yaml: data.secret is valid base64: a secret in the file?')
except (binascii.Error, ValueError):
    pass

def pods(docs):
    """(kind/name, pod spec, pod labels) of each workload"""
    for d in docs:
        if d['kind'] in ('Deployment', 'Job'):
            t = d['spec']['template']
            yield '%s/%s' % (d['kind'], d['metadata']['name']), t['spec'], t['metadata'].get('labels', {})

def check_pod(where, spec):
    """returns (program, args) of its one container"""
    (c,) = spec['containers']
    prog = c['command'][0]
    args = c['args']
    for a in args:
        if a.startswith('--') and a not in OPTS[prog]:
            err('%s: %s %s is not in its man page' % (where, prog, a))
    mounts = {m['name']: m['mountPath'] for m in c.get('volumeMounts', [])}
    vols = {v['name']: v for v in spec.get('volumes', [])}
    sf = args[args.index('--secret-file') + 1] if '--secret-file' in args else None
    if not sf:
        err('%s: no --secret-file' % where)
    else:
        ok = False
        for name, path in mounts.items():
            if sf.startswith(path.rstrip('/') + '/') and vols.get(name, {}).get('secret', {}).get('secretName') == 'portray-secret':
                ok = True
        if not ok:
            err('%s: --secret-file %s is not in a mounted Secret portray-secret' % (where, sf))
    for v in vols.values():
        if v['name'] not in mounts:
            err('%s: volume %s is not mounted' % (where, v['name']))
    if spec.get('securityContext', {}).get('runAsNonRoot') is not True:
        err('%s: not runAsNonRoot' % where)
    return prog, args, c

# per file: services select pods of the same file set
allpods = []
for n, docs in files.items():
    for d in docs:
        if d['kind'] == 'Deployment':
            sel = d['spec']['selector']['matchLabels']
            labels = d['spec']['template']['metadata']['labels']
            if any(labels.get(k) != v for k, v in sel.items()):
                err('%s: Deployment %s selector does not match its pods' % (n, d['metadata']['name']))
    for where, spec, labels in pods(docs):
        allpods.append((n, where, spec, labels))

def selected(svc, filename):
    sel = svc['spec']['selector']
    return [(w, s, l) for (n, w, s, l) in allpods if n == filename and all(l.get(k) == v for k, v in sel.items())]

def service(filename, name):
    for d in files[filename]:
        if d['kind'] == 'Service' and d['metadata']['name'] == name:
            return d
    err('%s: no Service %s' % (filename, name))
    return None

def arg(args, flag):
    return args[args.index(flag) + 1] if flag in args else None

# dialling: the master Job accepts on the Service's target port; workers dial the Service
msvc = service('portray-master-job.yaml', 'portray-master')
if msvc:
    sp = msvc['spec']['ports'][0]
    backs = selected(msvc, 'portray-master-job.yaml')
    if len(backs) != 1:
        err('Service portray-master selects %d workloads' % len(backs))
    for where, spec, labels in backs:
        prog, args, c = check_pod('portray-master-job.yaml ' + where, spec)
        acc = arg(args, '--accept')
        ports = {p['name']: p['containerPort'] for p in c.get('ports', [])}
        if prog != 'portray-master' or not acc:
            err('portray-master-job.yaml: the master does not --accept')
        elif ports.get(sp['targetPort']) != int(acc.rsplit(':', 1)[1]):
            err('Service portray-master targets %s, the master accepts on %s' % (sp['targetPort'], acc))
        if '--no-local' not in args:
            err('portray-master-job.yaml: the master traces too (no --no-local)')
    for n, where, spec, labels in allpods:
        if n == 'portray-worker-deployment.yaml':
            prog, args, c = check_pod(n + ' ' + where, spec)
            want = 'portray-master:%d' % sp['port']
            if arg(args, '--connect') != want:
                err('%s: workers dial %s, the Service is %s' % (n, arg(args, '--connect'), want))
            print('ok   %s dials %s: the Service of the master that accepts on %s' % (where, want, acc))

# headless: workers listen, the master names the headless Service
hsvc = service('portray-headless.yaml', 'portray-workers')
if hsvc:
    if hsvc['spec'].get('clusterIP') != 'None':
        err('Service portray-workers is not headless (clusterIP: None)')
    hp = hsvc['spec']['ports'][0]
    for where, spec, labels in selected(hsvc, 'portray-headless.yaml'):
        prog, args, c = check_pod('portray-headless.yaml ' + where, spec)
        lis = arg(args, '--listen')
        ports = {p['name']: p['containerPort'] for p in c.get('ports', [])}
        if prog != 'portray-worker' or not lis or ports.get(hp['targetPort']) != int(lis.rsplit(':', 1)[1]):
            err('portray-headless.yaml: the workers do not listen on the Service target port')
    for n, where, spec, labels in allpods:
        if n == 'portray-headless.yaml' and where.startswith('Job/'):
            prog, args, c = check_pod(n + ' ' + where, spec)
            want = 'portray-workers:%d' % hp['port']
            if arg(args, '-w') != want:
                err('%s: the master names %s, the headless Service is %s' % (n, arg(args, '-w'), want))
            print('ok   %s names -w %s: the headless Service of the listening workers' % (where, want))

if errors:
    print('\n'.join('FAIL: ' + e for e in errors))
    sys.exit(1)
print('ok')
PY
