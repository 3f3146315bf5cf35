scripts/merge-vs-time.sh 500000 2000
