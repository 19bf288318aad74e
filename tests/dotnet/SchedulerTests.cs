// Checklist items 35-41: the cyclic transmit list and its CanCyclicTXMsg objects.
using System.Collections.Generic;
using Ixxat.Vci3.Bal.Can;
using NUnit.Framework;

namespace Canemu.Tests
{
  public class SchedulerTests : DaemonFixture
  {
    Line alpha, beta;
    ICanScheduler list;

    [SetUp]
    public void OpenLines()
    {
      beta = new Line("beta");
      alpha = new Line("alpha");
      list = T.Open<ICanScheduler>(alpha.Bal);
    }

    [TearDown]
    public void CloseLines()
    {
      list.Dispose();
      alpha.Dispose();
      beta.Dispose();
    }

    static CanCyclicTXMsg Cyclic(uint id, ushort cycle, params byte[] data)
    {
      var m = new CanCyclicTXMsg { Identifier = id, CycleTicks = cycle, DataLength = (byte)data.Length };
      for (int i = 0; i < data.Length; i++) m[i] = data[i];
      return m;
    }

    // Cyclic(id, cycle, data), added to the list.
    CanCyclicTXMsg Added(uint id, ushort cycle, params byte[] data)
    {
      var m = Cyclic(id, cycle, data);
      list.AddMessage(m);
      return m;
    }

    // Adds `a` and `b`, starts each for three repetitions and runs the list for 10 ms: what beta
    // received.
    List<CanMessage> ThreeOfEach(CanCyclicTXMsg a, CanCyclicTXMsg b)
    {
      list.AddMessage(a);
      list.AddMessage(b);
      list.StartMessage(a, 3);
      list.StartMessage(b, 3);
      list.Resume();
      T.Step(10);
      return beta.Data();
    }

    // The tick (1 ms, counted from `from_us`) in which each frame of `id` went out.
    static List<long> Ticks(List<CanMessage> got, uint id, long fromUs)
    {
      var ticks = new List<long>();
      foreach (var m in got) if (m.Identifier == id) ticks.Add(((long)m.TimeStamp - fromUs) / 1000);
      return ticks;
    }

    [Test]
    public void Item35_SixteenObjectsCycleTicksInRangeTickOfAMillisecond()
    {
      Assert.AreEqual(1000000u, list.ClockFrequency);
      Assert.AreEqual(1000u, list.CyclicMessageTimeDivisor, "1 ms ticks");
      Assert.AreEqual(65535u, list.MaxCyclicMsgTicks);
      var e = T.Throws(() => list.AddMessage(Cyclic(0x1, 0)));
      Assert.AreEqual(0xE0010004u, e.ErrorCode);
      StringAssert.Contains("ICanScheduler.AddMessage(cycle 0", e.Message);
      var bad = Cyclic(0x1, 10, 0);
      bad.AutoIncrementMode = CanCyclicTXIncMode.Inc8;
      bad.AutoIncrementIndex = 8;
      e = T.Throws(() => list.AddMessage(bad));
      StringAssert.Contains("mode Inc8, index 8", e.Message);
      var all = new List<CanCyclicTXMsg>();
      for (uint i = 0; i < 16; i++)
      {
        var m = Cyclic(0x100 + i, 65535);
        list.AddMessage(m);
        all.Add(m);
      }
      e = T.Throws(() => list.AddMessage(Cyclic(0x200, 65535)));
      Assert.AreEqual(0xE0010003u, e.ErrorCode);
      StringAssert.Contains("no room: the list holds 16 messages", e.Message);
      list.RemMessage(all[3]);
      list.AddMessage(Cyclic(0x200, 65535));
      e = T.Throws(() => list.RemMessage(all[3]));
      StringAssert.Contains("was not added to this list", e.Message);
    }

    [Test]
    public void Item36_OneFramePerTickCollisionsTakeTheNextFreeTick()
    {
      var one = Added(0x1, 2, 1);
      var two = Added(0x2, 3, 2);
      list.StartMessage(one);
      list.StartMessage(two);
      long resumeUs = (long)(Emulator.Now / 1000);
      list.Resume();
      T.Step(20.5);
      var got = beta.Data();
      CollectionAssert.AreEqual(new long[] { 2, 4, 6, 8, 10, 12, 14, 16, 18, 20 }, Ticks(got, 0x1, resumeUs));
      CollectionAssert.AreEqual(new long[] { 3, 7, 9, 13, 15, 19 }, Ticks(got, 0x2, resumeUs),
                                "6, 12, 18 taken by object 1: one tick later, the rhythm kept");
    }

    [Test]
    public void Item37_AdmissionStopsWhereTheSharesWouldExceedOne()
    {
      list.AddMessage(Cyclic(0x1, 2));
      list.AddMessage(Cyclic(0x2, 3));
      list.AddMessage(Cyclic(0x3, 6));  // 1/2 + 1/3 + 1/6 = 1: admitted
      var e = T.Throws(() => list.AddMessage(Cyclic(0x4, 1000)));
      Assert.AreEqual(0xE0010003u, e.ErrorCode);
      StringAssert.Contains("the sum of 1/CycleTicks of its messages may not exceed 1", e.Message);
      list.Reset();
      list.AddMessage(Cyclic(0x5, 1));  // a cycle of 1 takes every tick
      T.Throws(() => list.AddMessage(Cyclic(0x6, 65535)));
    }

    [Test]
    public void Item38_IdleUntilStartedSuspendedUntilResumeResetRemovesAll()
    {
      var m = Added(0x10, 2, 1);
      Added(0x11, 2, 2);  // never started: idle
      list.StartMessage(m);
      T.Step(5);
      Assert.AreEqual(0, beta.Data().Count, "the task is suspended after open");
      list.Resume();
      T.Step(5.5);
      var got = beta.Data();
      Assert.AreEqual(2, got.Count, "ticks 2 and 4: the started one only");
      foreach (var x in got) Assert.AreEqual(0x10u, x.Identifier);
      list.Suspend();
      T.Step(5);
      Assert.AreEqual(0, beta.Data().Count, "suspended: nothing");
      list.Resume();
      T.Step(4.5);
      Assert.AreEqual(2, beta.Data().Count);
      list.StopMessage(m);
      T.Step(3);
      Assert.AreEqual(0, beta.Data().Count, "stopped");
      m.Start();
      T.Step(4.5);
      Assert.AreEqual(2, beta.Data().Count, "CanCyclicTXMsg.Start");
      list.Reset();
      T.Step(5);
      Assert.AreEqual(0, beta.Data().Count, "Reset halts");
      list.UpdateStatus();
      Assert.IsFalse(list.IsRunning);
      Assert.AreEqual(CanCyclicTXStatus.Empty, m.Status, "and removes");
      var e = T.Throws(() => list.StartMessage(m));
      StringAssert.Contains("was not added to this list", e.Message);
      list.AddMessage(m);  // the same object may come back
    }

    [Test]
    public void Item39_StatusChangesOnlyWithUpdateStatus()
    {
      var m = Added(0x10, 1, 1);
      Assert.AreEqual(CanCyclicTXStatus.Empty, m.Status);
      list.StartMessage(m, 3);
      list.Resume();
      Assert.AreEqual(CanCyclicTXStatus.Empty, m.Status, "no UpdateStatus yet");
      list.UpdateStatus();
      Assert.AreEqual(CanCyclicTXStatus.Busy, m.Status);
      Assert.IsTrue(list.IsRunning);
      T.Step(10);
      Assert.AreEqual(3, beta.Data().Count, "three repetitions");
      Assert.AreEqual(CanCyclicTXStatus.Busy, m.Status, "until asked");
      list.UpdateStatus();
      Assert.AreEqual(CanCyclicTXStatus.Done, m.Status);
    }

    [Test]
    public void Item40_IncIdWrapsAt2048And2To29()
    {
      var std = Cyclic(0x7FE, 2, 1);
      std.AutoIncrementMode = CanCyclicTXIncMode.IncId;
      var ext = Cyclic(0x1FFFFFFE, 2, 2);
      ext.ExtendedFrameFormat = true;
      ext.AutoIncrementMode = CanCyclicTXIncMode.IncId;
      var s = new List<uint>();
      var x = new List<uint>();
      foreach (var m in ThreeOfEach(std, ext)) (m.ExtendedFrameFormat ? x : s).Add(m.Identifier);
      CollectionAssert.AreEqual(new uint[] { 0x7FE, 0x7FF, 0x000 }, s);
      CollectionAssert.AreEqual(new uint[] { 0x1FFFFFFE, 0x1FFFFFFF, 0x0 }, x);
    }

    [Test]
    public void Item41_Inc8AndInc16CountTheirBytesLittleEndian()
    {
      var eight = Cyclic(0x20, 2, 0xAA, 0xFE, 0xBB);
      eight.AutoIncrementMode = CanCyclicTXIncMode.Inc8;
      eight.AutoIncrementIndex = 1;
      var sixteen = Cyclic(0x21, 2, 0xCC, 0xDD, 0xFE, 0xFF);
      sixteen.AutoIncrementMode = CanCyclicTXIncMode.Inc16;
      sixteen.AutoIncrementIndex = 2;
      var e8 = new List<string>();
      var e16 = new List<string>();
      foreach (var m in ThreeOfEach(eight, sixteen))
      {
        string bytes = "";
        for (int i = 0; i < m.DataLength; i++) bytes += m[i].ToString("X2");
        (m.Identifier == 0x20 ? e8 : e16).Add(bytes);
      }
      CollectionAssert.AreEqual(new[] { "AAFEBB", "AAFFBB", "AA00BB" }, e8);
      CollectionAssert.AreEqual(new[] { "CCDDFEFF", "CCDDFFFF", "CCDD0000" }, e16);
    }
  }
}
