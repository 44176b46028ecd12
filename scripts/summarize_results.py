#!/usr/bin/env python3
"""Counts test cases in the JUnit XML files under a results folder and prints
`N passed, N failed, N skipped`; exits 1 when any failed or nothing ran."""
import glob
import os
import sys
import xml.etree.ElementTree as ET


def main(results_dir):
    passed = failed = skipped = 0
    failures = []
    files = sorted(glob.glob(os.path.join(results_dir, '**', '*.xml'), recursive=True))
    for path in files:
        try:
            root = ET.parse(path).getroot()
        except ET.ParseError as exc:
            failed += 1
            failures.append('%s: unreadable result file (%s)' % (path, exc))
            continue
        cases = root.iter('testcase')
        found = False
        for case in cases:
            found = True
            name = '%s.%s' % (case.get('classname', ''), case.get('name', ''))
            if case.find('failure') is not None or case.find('error') is not None:
                failed += 1
                failures.append(name + '  (' + os.path.basename(path) + ')')
            elif case.find('skipped') is not None or case.get('status') == 'notrun':
                skipped += 1
            else:
                passed += 1
        if not found and (int(root.get('failures', 0) or 0) or int(root.get('errors', 0) or 0)):
            failed += 1
            failures.append(os.path.basename(path) + ': test did not run')
    for f in failures:
        print('FAILED: ' + f)
    print('%d passed, %d failed, %d skipped' % (passed, failed, skipped))
    return 1 if failed or passed == 0 else 0


if __name__ == '__main__':
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else 'build/test_results'))
